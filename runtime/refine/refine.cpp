// Output-error refinement by Ceres' Levenberg-Marquardt (see refine.hpp).
#include "runtime/refine/refine.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <ceres/ceres.h>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <memory>

#include "ir/queries.hpp"
#include "runtime/operators/noise_level.hpp"
#include "runtime/records/sampling.hpp"
#include "runtime/simulate/initial_state.hpp"
#include "runtime/simulate/validate.hpp"
#include "runtime/solve/residual_correlation.hpp"

namespace sidc {
namespace {

// One record's weighted output errors as a Ceres cost: parameter blocks are the model's
// parameters (shared by every record) and this record's initial state.
class RecordCost final : public ceres::CostFunction {
 public:
  RecordCost(const ir::Model& model, const ExplicitForm& form, RecordRun run, std::vector<double> weights)
      : model_(model), form_(form), run_(std::move(run)), weights_(std::move(weights)) {
    set_num_residuals(static_cast<int>(rows() * form.outputs.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(model.parameters.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(state_size()));
  }

  std::size_t rows() const { return run_.options.time.size(); }
  std::size_t state_size() const { return form_.state_size(); }
  const RecordRun& run() const { return run_; }

  std::map<std::string, std::vector<double>> state_map(const double* x) const {
    return sidc::state_map(form_, std::span<const double>(x, state_size()));
  }

  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    const bool jacobian = jacobians != nullptr && (jacobians[0] != nullptr || jacobians[1] != nullptr);
    const std::size_t k = form_.outputs.size(), p = model_.parameters.size(), n = state_size();
    // Levenberg-Marquardt accepts most trial steps and then asks for the Jacobian at the point it has
    // just evaluated: every run integrates the sensitivities too, and the last is kept for that request.
    std::vector<double> key(x[0], x[0] + p);
    key.insert(key.end(), x[1], x[1] + n);
    if (key != cached_key_) {
      SimulateOptions& o = run_.options;
      o.parameters.assign(x[0], x[0] + p);
      o.initial = state_map(x[1]);
      o.sensitivities = true;
      cached_ok_ = !simulate_into(model_, form_, o, cached_).has_value() && cached_.completed();
      cached_key_ = std::move(key);
    }
    if (!cached_ok_) return false;  // a rejected trial step: Ceres shrinks its trust region
    const SimulationSummary* s = &cached_;
    const std::size_t columns = s->sensitivity_columns;
    for (std::size_t i = 0; i < rows(); ++i)
      for (std::size_t j = 0; j < k; ++j) {
        const std::size_t row = i * k + j;
        residuals[row] = weights_[j] * (run_.recorded[j][i] - s->outputs[j][i]);
        if (!std::isfinite(residuals[row])) return false;
        if (!jacobian) continue;
        const double* ds = &s->sensitivity[j][i * columns];
        if (jacobians[0])
          for (std::size_t q = 0; q < p; ++q) jacobians[0][row * p + q] = -weights_[j] * ds[q];
        if (jacobians[1])
          for (std::size_t q = 0; q < n; ++q) jacobians[1][row * n + q] = -weights_[j] * ds[p + q];
      }
    return true;
  }

  const SimulationSummary* last_run() const { return cached_ok_ ? &cached_ : nullptr; }
  // Why the last run gave no usable residuals.
  std::string last_failure() const {
    if (!cached_.completed()) return cached_.message;
    return "its solution is not finite";
  }

  double rms(std::size_t output, const SimulationSummary& s) const {
    double total = 0;
    for (std::size_t i = 0; i < rows(); ++i) total += std::pow(run_.recorded[output][i] - s.outputs[output][i], 2);
    return std::sqrt(total / static_cast<double>(rows()));
  }

 private:
  const ir::Model& model_;
  const ExplicitForm& form_;
  mutable RecordRun run_;  // its SimulateOptions take each trial's parameters and state
  mutable SimulationSummary cached_;        // the last run, with sensitivities (its arrays reused by the next)
  mutable bool cached_ok_ = false;          // it completed
  mutable std::vector<double> cached_key_;  // at these parameters, then initial state
  std::vector<double> weights_;
};

// Gauss-Newton's standard errors of the first `parameters` unknowns: sigma^2 (J^T J)^-1, the
// columns scaled to unit length first so that parameters of very different size do not make an
// invertible J^T J look singular. NaN for all when J is rank deficient.
std::vector<double> standard_errors(const Eigen::MatrixXd& jacobian, double sigma2, std::size_t parameters) {
  const Eigen::Index p = jacobian.cols();
  Eigen::VectorXd scale(p);
  for (Eigen::Index c = 0; c < p; ++c) {
    const double norm = jacobian.col(c).norm();
    scale(c) = norm > 0 ? 1 / norm : 0;
  }
  const Eigen::MatrixXd scaled = jacobian * scale.asDiagonal();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(scaled);
  qr.setThreshold(1e-12);
  std::vector<double> out(parameters, std::numeric_limits<double>::quiet_NaN());
  if (qr.rank() < p || scale.minCoeff() == 0) return out;
  const Eigen::MatrixXd r = qr.matrixR().topLeftCorner(p, p).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd r_inverse = r.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(p, p));
  const Eigen::MatrixXd permuted = qr.colsPermutation() * r_inverse;  // (J^T J)^-1 = P R^-1 R^-T P^T
  for (std::size_t q = 0; q < parameters; ++q) {
    const auto Q = static_cast<Eigen::Index>(q);
    out[q] = scale(Q) * std::sqrt(sigma2 * permuted.row(Q).squaredNorm());
  }
  return out;
}

// RK4 steps per sample interval, from the data: the fewest of 1, 2, 4, 8 whose run at the start
// differs from a run with twice as many steps by at most a hundredth of each output's noise (a
// millionth of its spread on a noise-free record), so that the solver's error never competes
// with the noise while a finely sampled record is not stepped four times per sample for nothing.
// Nullopt when the start cannot be solved (refine() then says why).
std::optional<int> substeps_for(const ir::Model& model, const ExplicitForm& form, RecordRun run, const std::vector<double>& tolerance) {
  auto outputs = [&](int substeps) -> std::optional<std::vector<std::vector<double>>> {
    run.options.substeps = substeps;
    auto r = simulate(model, form, run.options);
    if (!std::holds_alternative<SimulationSummary>(r) || !std::get<SimulationSummary>(r).completed()) return std::nullopt;
    return std::get<SimulationSummary>(std::move(r)).outputs;
  };
  auto coarse = outputs(1);
  if (!coarse) return std::nullopt;
  int substeps = 1;
  for (; substeps < 8; substeps *= 2) {
    auto fine = outputs(2 * substeps);
    if (!fine) return std::nullopt;
    double worst = 0;
    for (std::size_t j = 0; j < coarse->size(); ++j)
      for (std::size_t i = 0; i < (*coarse)[j].size(); ++i) worst = std::max(worst, std::abs((*coarse)[j][i] - (*fine)[j][i]) / tolerance[j]);
    if (worst <= 1) break;
    coarse = std::move(fine);
  }
  return substeps;
}

// `record`'s samples in `rows` (the fit's window, records/sampling.hpp's time_window): the
// refinement is fitted where the equation-error fit was, and a section held out for testing stays
// out of both.
SampledRecord window_of(const SampledRecord& record, IndexRange rows) {
  const auto a = static_cast<std::ptrdiff_t>(rows.begin), b = static_cast<std::ptrdiff_t>(rows.end);
  SampledRecord w = record;
  w.time.assign(record.time.begin() + a, record.time.begin() + b);
  for (auto& [name, values] : w.signals) values.assign(record.signals.at(name).begin() + a, record.signals.at(name).begin() + b);
  if (!w.weights.empty()) w.weights.assign(record.weights.begin() + a, record.weights.begin() + b);
  return w;
}

}  // namespace

const char* to_string(RefineSummary::Status status) {
  switch (status) {
    case RefineSummary::Status::converged: return "converged";
    case RefineSummary::Status::stopped: return "stopped at the iteration limit";
    case RefineSummary::Status::failed: return "failed";
  }
  return "?";
}

std::variant<RefineSummary, Diagnostic> refine(const ir::Model& normalized, const ExplicitForm& form, const std::vector<double>& linear,
                                               const std::vector<const SampledRecord*>& records, const RefineOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  RefineSummary summary;
  summary.values = linear;
  for (std::size_t q = 0; q < normalized.parameters.size(); ++q)
    summary.parameters.push_back({normalized.parameters[q].name, linear[q], linear[q], std::numeric_limits<double>::quiet_NaN(),
                                  parameter_unit(normalized, normalized.parameters[q].name)});

  ValidationOptions v;
  v.substeps = options.substeps > 0 ? options.substeps : 4;  // for the start's estimate; the refinement's own is chosen below
  v.evaluation = options.evaluation;
  v.max_samples = options.max_samples;
  std::vector<std::unique_ptr<RecordCost>> costs;
  std::vector<std::vector<double>> states;  // per record, the initial-state block
  std::vector<SampledRecord> windows;  // the records cut to the fit window, when it is set
  windows.reserve(records.size());
  for (const SampledRecord* whole : records) {
    const SampledRecord* record = whole;
    IndexRange rows{0, whole->time.size()};
    if (options.from || options.to) {
      rows = time_window(whole->time, options.from.value_or(-std::numeric_limits<double>::infinity()),
                         options.to.value_or(std::numeric_limits<double>::infinity()));
      windows.push_back(window_of(*whole, rows));
      record = &windows.back();
    }
    auto prepared = record_run(normalized, form, linear, *record, v);
    if (auto* d = std::get_if<Diagnostic>(&prepared)) return *d;
    RecordRun& run = std::get<RecordRun>(prepared);
    // The start: the validation's estimate over the start segment with the linear parameters.
    if (run.options.time.size() >= 2)
      run.options.initial = estimate_initial_state(normalized, form, run.options, run.recorded, start_segment_samples(run.options.time.size())).initial;
    std::vector<double> weights, tolerance;
    for (std::size_t j = 0; j < form.outputs.size(); ++j) {
      const NoiseLevel noise = estimate_noise_level(run.recorded[j]);
      // A noise-free record (sigma 0) weighs by its spread instead, so every output still counts.
      const bool noisy = noise.sigma > 1e-9 * noise.spread;
      const double spread = noise.spread > 0 ? noise.spread : 1.0;
      const double s = noisy ? noise.sigma : spread;
      weights.push_back(1 / s);
      tolerance.push_back(noisy ? 0.01 * noise.sigma : 1e-6 * spread);
      if (costs.empty()) summary.output_noise.emplace_back(form.outputs[j].name, s);
    }
    if (options.substeps > 0) run.options.substeps = options.substeps;
    else if (auto chosen = substeps_for(normalized, form, run, tolerance)) run.options.substeps = *chosen;
    summary.substeps.push_back(run.options.substeps);
    RefinedRecord r;
    r.path = record->path;
    r.first_sample = rows.begin + run.start;
    r.samples = run.options.time.size();
    costs.push_back(std::make_unique<RecordCost>(normalized, form, std::move(run), std::move(weights)));
    states.push_back(state_vector(form, costs.back()->run().options.initial));
    summary.records.push_back(std::move(r));
  }

  std::vector<double> parameters = linear;
  const std::size_t p = parameters.size();
  auto finish = [&]() -> RefineSummary {
    summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return summary;
  };
  // The start must run: without a solution of the linear estimate's equations there is nothing to refine.
  double cost_before = 0;
  for (std::size_t r = 0; r < costs.size(); ++r) {
    // This run (with sensitivities) is also the one Ceres asks for first: RecordCost keeps it.
    std::vector<double> residuals(static_cast<std::size_t>(costs[r]->num_residuals()));
    const double* blocks[2] = {parameters.data(), states[r].data()};
    if (!costs[r]->Evaluate(blocks, residuals.data(), nullptr)) {
      summary.message = fmt::format("the equation-error estimate's equations cannot be solved over {} ({}); its estimate is kept",
                                    records[r]->path, costs[r]->last_failure());
      return finish();
    }
    for (double e : residuals) cost_before += 0.5 * e * e;
    for (std::size_t j = 0; j < form.outputs.size(); ++j)
      summary.records[r].rms_before.emplace_back(form.outputs[j].name, costs[r]->rms(j, *costs[r]->last_run()));
    summary.residuals += residuals.size();
  }
  summary.cost_before = cost_before;
  summary.unknowns = p + costs.size() * form.state_size();

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (std::size_t r = 0; r < costs.size(); ++r) problem.AddResidualBlock(costs[r].get(), nullptr, parameters.data(), states[r].data());
  ceres::Solver::Options solver;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.parameter_tolerance = options.parameter_tolerance;
  solver.gradient_tolerance = options.gradient_tolerance;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  solver.num_threads = 1;  // each evaluation is one sequential simulation
  ceres::Solver::Summary result;
  ceres::Solve(solver, &problem, &result);
  summary.iterations = static_cast<int>(result.iterations.size()) - 1;

  const bool usable = result.IsSolutionUsable() && result.final_cost <= cost_before;
  if (!usable) {
    summary.message = fmt::format("Levenberg-Marquardt did not improve on the equation-error estimate ({}); that estimate is kept",
                                  result.message);
    return finish();
  }
  summary.status = result.termination_type == ceres::CONVERGENCE ? RefineSummary::Status::converged : RefineSummary::Status::stopped;
  summary.message = summary.status == RefineSummary::Status::converged
                        ? fmt::format("converged after {} iterations", summary.iterations)
                        : fmt::format("stopped after {} iterations without meeting the convergence tests ({}); the last estimate is reported",
                                      summary.iterations, result.message);
  summary.cost_after = result.final_cost;
  summary.values = parameters;

  // The Jacobian at the estimate, for the covariance and the final errors.
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(summary.residuals), static_cast<Eigen::Index>(summary.unknowns));
  Eigen::Index row = 0;
  std::vector<std::vector<std::vector<double>>> output_errors(form.outputs.size());  // per output, per record
  for (std::size_t r = 0; r < costs.size(); ++r) {
    const std::size_t m = static_cast<std::size_t>(costs[r]->num_residuals()), n = costs[r]->state_size();
    std::vector<double> residuals(m), jp(m * p), jx(m * n);
    const double* blocks[2] = {parameters.data(), states[r].data()};
    double* jacobians[2] = {jp.data(), jx.data()};
    if (!costs[r]->Evaluate(blocks, residuals.data(), jacobians)) {
      summary.message += "; the estimate's run failed when its Jacobian was evaluated, so no intervals";
      jacobian.resize(0, 0);
      break;
    }
    for (std::size_t i = 0; i < m; ++i) {
      for (std::size_t q = 0; q < p; ++q) jacobian(row + static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(q)) = jp[i * p + q];
      for (std::size_t q = 0; q < n; ++q)
        jacobian(row + static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(p + r * n + q)) = jx[i * n + q];
    }
    row += static_cast<Eigen::Index>(m);
    const SimulationSummary* s = costs[r]->last_run();  // the run Evaluate just made
    for (std::size_t j = 0; j < form.outputs.size() && s; ++j) {
      summary.records[r].rms_after.emplace_back(form.outputs[j].name, costs[r]->rms(j, *s));
      std::vector<double> e(costs[r]->rows());
      for (std::size_t i = 0; i < e.size(); ++i) e[i] = costs[r]->run().recorded[j][i] - s->outputs[j][i];
      output_errors[j].push_back(std::move(e));
    }
    summary.records[r].initial = costs[r]->state_map(states[r].data());
    summary.records[r].initial_state = named_state(form, summary.records[r].initial);
  }
  // The intervals assume white output errors (measurement noise): test each output's, record by
  // record, as the fit's residual analysis tests the equation residuals.
  summary.output_error_white = true;
  for (std::size_t j = 0; j < output_errors.size(); ++j) {
    if (output_errors[j].empty()) continue;
    const ResidualCorrelationSummary c = residual_correlation(output_errors[j], {}, ResidualCorrelationOptions{});
    if (!c.is_usable()) continue;
    summary.output_error_white = summary.output_error_white && c.autocorrelation.white;
    summary.whiteness.emplace_back(form.outputs[j].name, c.autocorrelation.verdict);
  }
  if (jacobian.size() > 0 && summary.residuals > summary.unknowns) {
    const double sigma2 = 2 * summary.cost_after / static_cast<double>(summary.residuals - summary.unknowns);
    const std::vector<double> se = standard_errors(jacobian, sigma2, p);
    for (std::size_t q = 0; q < p; ++q) summary.parameters[q].standard_error = se[q];
  }
  for (std::size_t q = 0; q < p; ++q) summary.parameters[q].refined = parameters[q];
  return finish();
}

std::string RefineSummary::report() const {
  std::string out = "Refined by the output error (thesis section 2-4's simulation as the fit criterion: Levenberg-Marquardt over the\n"
                    "parameters and each record's initial state, exact sensitivities):\n";
  if (status == Status::failed) return out + "  not refined: " + message + ".\n";
  out += fmt::format("  {}; weighted cost {:.6g} -> {:.6g} over {} output samples, {} unknowns\n", message, cost_before, cost_after,
                     residuals, unknowns);
  if (!substeps.empty())
    out += fmt::format("  solved by RK4 with {} step(s) per sample interval (the fewest whose error stays below a hundredth of the noise)\n",
                       substeps.front());
  std::size_t width = 9;
  for (const auto& q : parameters) width = std::max(width, q.name.size());
  const bool units = std::any_of(parameters.begin(), parameters.end(), [](const RefinedParameter& q) { return !q.unit.empty(); });
  out += fmt::format("  {:<{}}  {:>14}  {:>14}  {:>12}  {:>29}{}\n", "parameter", width, "equation error", "refined", "std. error", "95% interval",
                     units ? "  unit" : "");
  for (const auto& q : parameters) {
    const bool known = std::isfinite(q.standard_error);
    out += fmt::format("  {:<{}}  {:>14.7g}  {:>14.7g}  {:>12}  {:>29}{}\n", q.name, width, q.linear, q.refined,
                       known ? fmt::format("{:.3g}", q.standard_error) : "-",
                       known ? fmt::format("[{:.7g}, {:.7g}]", q.refined - 1.96 * q.standard_error, q.refined + 1.96 * q.standard_error) : "-",
                       q.unit.empty() ? "" : "  " + q.unit);
  }
  for (const auto& r : records) {
    out += fmt::format("  {}: from sample {}, {} samples;", r.path, r.first_sample, r.samples);
    for (std::size_t j = 0; j < r.rms_after.size() && j < r.rms_before.size(); ++j)
      out += fmt::format(" {} RMS error {:.4g} -> {:.4g};", r.rms_after[j].first, r.rms_before[j].second, r.rms_after[j].second);
    out += " initial state";
    for (const auto& [name, value] : r.initial_state) out += fmt::format(" {} = {:.6g}", name, value);
    out += "\n";
  }
  for (const auto& [output, verdict] : whiteness) out += fmt::format("  output error of {}: {}\n", output, verdict);
  if (output_error_white)
    out += "  The intervals are Gauss-Newton's from the output error, which is the record's measurement noise when the\n"
           "  model is right, and it looks white: their assumption holds.\n";
  else
    out += "  The intervals are Gauss-Newton's from the output error and assume it white; it is not: the model misses part of\n"
           "  the record, or the noise is coloured, and the intervals are too narrow. The solved equations against the\n"
           "  record (validation) are the test to trust.\n";
  return out;
}

}  // namespace sidc
