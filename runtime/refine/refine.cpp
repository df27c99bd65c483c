// Output-error refinement by Ceres' Levenberg-Marquardt (see refine.hpp).
#include "runtime/refine/refine.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <ceres/ceres.h>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <memory>
#include <optional>

#include "ir/queries.hpp"
#include "runtime/operators/noise_level.hpp"
#include "runtime/records/sampling.hpp"
#include "runtime/simulate/initial_state.hpp"
#include "runtime/simulate/validate.hpp"
#include "runtime/solve/residual_correlation.hpp"

namespace sidc {
namespace {

// Multiple shooting: the shortest segment (samples), and the weight of a continuity defect against
// one sample's output error (a defect of a thousandth of the noise costs as much as one sample's
// noise-sized error, so the joined segments end up continuous to well below the noise; at 100 the
// minimum moved by a tenth of a standard error from single shooting's on a record both solve).
constexpr std::size_t kMinShootingSamples = 20;
constexpr double kContinuityWeight = 1000;

// One record's weighted output errors as a Ceres cost: parameter blocks are the model's
// parameters (shared by every record) and this record's initial state.
class RecordCost final : public ceres::CostFunction {
 public:
  // `compared`: the first samples of the run compared with the record (all of them, or all but the
  // last for a shooting segment whose last sample is the next segment's first).
  RecordCost(const ir::Model& model, const ExplicitForm& form, RecordRun run, std::vector<double> weights, std::size_t compared)
      : model_(model), form_(form), run_(std::move(run)), weights_(std::move(weights)), compared_(compared) {
    set_num_residuals(static_cast<int>(rows() * form.outputs.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(model.parameters.size()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(state_size()));
  }

  std::size_t rows() const { return compared_; }
  const std::vector<double>& weights() const { return weights_; }

  // The run (with sensitivities) at parameters x0 and initial state x1; null when it fails. Levenberg-
  // Marquardt accepts most trial steps and then asks for the Jacobian at the point it has just
  // evaluated, and a shooting segment's continuity cost asks for the same run: the last is kept.
  const SimulationSummary* run_at(const double* x0, const double* x1) const {
    const std::size_t p = model_.parameters.size(), n = state_size();
    std::vector<double> key(x0, x0 + p);
    key.insert(key.end(), x1, x1 + n);
    if (key != cached_key_) {
      SimulateOptions& o = run_.options;
      o.parameters.assign(x0, x0 + p);
      o.initial = state_map(x1);
      o.sensitivities = true;
      cached_ok_ = !simulate_into(model_, form_, o, cached_).has_value() && cached_.completed();
      cached_key_ = std::move(key);
    }
    return cached_ok_ ? &cached_ : nullptr;
  }
  std::size_t state_size() const { return form_.state_size(); }
  const RecordRun& run() const { return run_; }

  std::map<std::string, std::vector<double>> state_map(const double* x) const {
    return sidc::state_map(form_, std::span<const double>(x, state_size()));
  }

  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    const bool jacobian = jacobians != nullptr && (jacobians[0] != nullptr || jacobians[1] != nullptr);
    const std::size_t k = form_.outputs.size(), p = model_.parameters.size(), n = state_size();
    const SimulationSummary* s = run_at(x[0], x[1]);
    if (!s) return false;  // a rejected trial step: Ceres shrinks its trust region
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

  // Why the last run gave no usable residuals.
  std::string last_failure() const {
    if (!cached_.completed()) return cached_.message;
    return "its solution is not finite";
  }

 private:
  const ir::Model& model_;
  const ExplicitForm& form_;
  mutable RecordRun run_;  // its SimulateOptions take each trial's parameters and state
  mutable SimulationSummary cached_;        // the last run, with sensitivities (its arrays reused by the next)
  mutable bool cached_ok_ = false;          // it completed
  mutable std::vector<double> cached_key_;  // at these parameters, then initial state
  std::vector<double> weights_;
  std::size_t compared_ = 0;
};

// Multiple shooting's join of two segments of one record: the state the first segment's run ends
// in against the next segment's initial state, component m weighted by w_m (see refine()). Its
// Jacobian comes from the first run's final sensitivities (SimulationSummary::final_vector).
class ContinuityCost final : public ceres::CostFunction {
 public:
  ContinuityCost(const RecordCost& from, std::size_t parameters, std::vector<double> weights)
      : from_(from), p_(parameters), weights_(std::move(weights)) {
    const auto n = static_cast<int>(weights_.size());
    set_num_residuals(n);
    mutable_parameter_block_sizes()->push_back(static_cast<int>(p_));
    mutable_parameter_block_sizes()->push_back(n);
    mutable_parameter_block_sizes()->push_back(n);
  }

  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    const std::size_t n = weights_.size();
    const SimulationSummary* run = from_.run_at(x[0], x[1]);
    if (!run || run->final_vector.size() < n * (1 + p_ + n)) return false;
    const std::vector<double>& f = run->final_vector;  // the state, then d state / d q by column
    for (std::size_t m = 0; m < n; ++m) {
      residuals[m] = weights_[m] * (f[m] - x[2][m]);
      if (!std::isfinite(residuals[m])) return false;
      if (!jacobians) continue;
      if (jacobians[0])
        for (std::size_t q = 0; q < p_; ++q) jacobians[0][m * p_ + q] = weights_[m] * f[n + q * n + m];
      if (jacobians[1])
        for (std::size_t q = 0; q < n; ++q) jacobians[1][m * n + q] = weights_[m] * f[n + (p_ + q) * n + m];
      if (jacobians[2])
        for (std::size_t q = 0; q < n; ++q) jacobians[2][m * n + q] = q == m ? -weights_[m] : 0.0;
    }
    return true;
  }

  // The largest |defect| over the components, in units of the first output's noise (w_m / lambda).
  double largest_defect(const double* x0, const double* x1, const double* x2, double lambda) const {
    const SimulationSummary* run = from_.run_at(x0, x1);
    if (!run || run->final_vector.size() < weights_.size()) return std::numeric_limits<double>::quiet_NaN();
    double worst = 0;
    for (std::size_t m = 0; m < weights_.size(); ++m) worst = std::max(worst, std::abs(weights_[m] / lambda * (run->final_vector[m] - x2[m])));
    return worst;
  }

 private:
  const RecordCost& from_;
  std::size_t p_;
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
                                  parameter_unit(normalized, normalized.parameters[q].name), normalized.parameters[q].nonlinear});

  ValidationOptions v;
  v.substeps = options.substeps > 0 ? options.substeps : 4;  // for the start's estimate; the refinement's own is chosen below
  v.evaluation = options.evaluation;
  v.max_samples = options.max_samples;
  // Shooting segments, record after record: one per record (single shooting), or several joined
  // by continuity costs (multiple shooting).
  struct Segment {
    std::size_t record = 0;
    std::unique_ptr<RecordCost> cost;
    std::vector<double> state;  // its initial-state block
  };
  std::vector<Segment> segments;
  std::vector<std::unique_ptr<ContinuityCost>> joins;
  std::vector<std::pair<std::size_t, std::size_t>> joined;  // segment indices each join connects
  std::vector<SampledRecord> windows;  // the records cut to the fit window, when it is set
  windows.reserve(records.size());
  for (std::size_t ri = 0; ri < records.size(); ++ri) {
    const SampledRecord* whole = records[ri];
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
    const std::size_t total = run.options.time.size();
    // The start: the validation's estimate over the start segment with the linear parameters.
    if (total >= 2) run.options.initial = estimate_initial_state(normalized, form, run.options, run.recorded, start_segment_samples(total)).initial;
    std::vector<double> weights, tolerance;
    for (std::size_t j = 0; j < form.outputs.size(); ++j) {
      const NoiseLevel noise = estimate_noise_level(run.recorded[j]);
      // A noise-free record (sigma 0) weighs by its spread instead, so every output still counts.
      const bool noisy = noise.sigma > 1e-9 * noise.spread;
      const double spread = noise.spread > 0 ? noise.spread : 1.0;
      const double s = noisy ? noise.sigma : spread;
      weights.push_back(1 / s);
      tolerance.push_back(noisy ? 0.01 * noise.sigma : 1e-6 * spread);
      if (segments.empty()) summary.output_noise.emplace_back(form.outputs[j].name, s);
    }
    // Segments: RefineOptions::segments of them (at least kMinShootingSamples samples each: shorter
    // ones carry too little of the record to pin their own initial state), one (single shooting),
    // or (automatic) segments of half the span the equation-error estimate's equations stay solvable
    // over from the record's start when they do not last the whole record (an unstable or badly
    // started run: multiple shooting). They share their ends, the record's intervals shared out evenly.
    std::optional<int> chosen;  // RK4 steps per sample interval, from the data (options.substeps 0)
    std::size_t pieces = 1;
    if (options.segments > 1) {
      pieces = std::max<std::size_t>(1, std::min<std::size_t>(static_cast<std::size_t>(options.segments), (total - 1) / kMinShootingSamples));
    } else if (options.substeps == 0) {
      chosen = substeps_for(normalized, form, run, tolerance);  // nullopt: the run did not last
      if (!chosen && options.segments == 0 && total >= 2 * kMinShootingSamples) {
        auto trial = simulate(normalized, form, run.options);
        if (auto* t = std::get_if<SimulationSummary>(&trial); t && !t->completed() && t->stopped_at) {
          const auto lasted = static_cast<std::size_t>(
              std::lower_bound(run.options.time.begin(), run.options.time.end(), *t->stopped_at) - run.options.time.begin());
          const std::size_t length = std::min(std::max(kMinShootingSamples, lasted / 2), total);
          pieces = length >= total ? 1 : (total - 1 + length - 2) / (length - 1);
          summary.shooting_reason = fmt::format("the equation-error estimate's equations, solved from the start of {}, stop at t = {:.6g} ({})",
                                                record->path, *t->stopped_at, t->message);
        }
      }
    }
    // Segment k covers grid samples [bound(k), bound(k + 1)], the intervals shared out evenly.
    const auto bound = [&](std::size_t k) { return k * (total - 1) / pieces; };
    if (pieces > 1 && options.substeps == 0)  // the steps from the first segment's run
      chosen = substeps_for(normalized, form, RecordRun{run.options.samples(0, bound(1) + 1), {}, run.start, false, {}}, tolerance);
    if (options.substeps > 0) run.options.substeps = options.substeps;
    else if (chosen) run.options.substeps = *chosen;
    summary.substeps.push_back(run.options.substeps);
    RefinedRecord r;
    r.path = record->path;
    r.first_sample = rows.begin + run.start;
    r.samples = total;
    r.segments = pieces;
    summary.records.push_back(std::move(r));
    for (std::size_t k = 0; k < pieces; ++k) {
      const std::size_t a = bound(k), b = bound(k + 1) + 1;  // [a, b), sharing b - 1 with the next (bound(pieces) = total - 1)
      const bool last = k + 1 == pieces;
      RecordRun piece{run.options.samples(a, b), {}, run.start + a, false, {}};
      for (const auto& column : run.recorded)
        piece.recorded.emplace_back(column.begin() + static_cast<std::ptrdiff_t>(a), column.begin() + static_cast<std::ptrdiff_t>(b));
      if (k > 0) {
        // A later segment starts from the record: its moving-arc state, improved by least squares
        // over the segment's first samples with the linear parameters.
        auto guess = initial_state_from_record(form, *record, options.evaluation, run.start + a);
        if (auto* d = std::get_if<Diagnostic>(&guess)) return *d;
        piece.options.initial = std::get<std::map<std::string, std::vector<double>>>(std::move(guess));
        piece.options.initial = estimate_initial_state(normalized, form, piece.options, piece.recorded, start_segment_samples(b - a)).initial;
      }
      Segment seg{ri, std::make_unique<RecordCost>(normalized, form, std::move(piece), weights, last ? b - a : b - a - 1), {}};
      seg.state = state_vector(form, seg.cost->run().options.initial);
      segments.push_back(std::move(seg));
      if (k > 0) {
        // Continuity of every state component, weighted like its output's samples times
        // kContinuityWeight and, for the derivative of order d, times the step^d (y' * h is in y's units).
        const double h = total > 1 ? run.options.time[1] - run.options.time[0] : 1.0;
        std::vector<double> w;
        for (std::size_t j = 0; j < form.outputs.size(); ++j)
          for (int d = 0; d < form.outputs[j].order; ++d) w.push_back(kContinuityWeight * weights[j] * std::pow(h, d));
        joins.push_back(std::make_unique<ContinuityCost>(*segments[segments.size() - 2].cost, normalized.parameters.size(), std::move(w)));
        joined.emplace_back(segments.size() - 2, segments.size() - 1);
      }
    }
  }

  std::vector<double> parameters = linear;
  const std::size_t p = parameters.size();
  auto finish = [&]() -> RefineSummary {
    summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return summary;
  };
  // Per record, each output's errors over its segments in time order (each shared end once).
  const auto record_errors = [&](std::size_t record, std::size_t output, bool& ok) {
    std::vector<double> e;
    for (const auto& seg : segments) {
      if (seg.record != record) continue;
      const SimulationSummary* s = seg.cost->run_at(parameters.data(), seg.state.data());
      if (!s) {
        ok = false;
        return e;
      }
      for (std::size_t i = 0; i < seg.cost->rows(); ++i) e.push_back(seg.cost->run().recorded[output][i] - s->outputs[output][i]);
    }
    return e;
  };
  const auto rms_of = [](const std::vector<double>& e) {
    double total = 0;
    for (double x : e) total += x * x;
    return e.empty() ? 0.0 : std::sqrt(total / static_cast<double>(e.size()));
  };
  // The start must run: without a solution of the linear estimate's equations there is nothing to refine.
  double cost_before = 0;
  for (auto& seg : segments) {
    // This run (with sensitivities) is also the one Ceres asks for first: RecordCost keeps it.
    std::vector<double> residuals(static_cast<std::size_t>(seg.cost->num_residuals()));
    const double* blocks[2] = {parameters.data(), seg.state.data()};
    if (!seg.cost->Evaluate(blocks, residuals.data(), nullptr)) {
      summary.message = fmt::format("the equation-error estimate's equations cannot be solved over {}{} ({}); its estimate is kept",
                                    summary.records[seg.record].path,
                                    summary.records[seg.record].segments > 1 ? fmt::format(" from t = {:.6g}", seg.cost->run().options.time.front()) : "",
                                    seg.cost->last_failure());
      return finish();
    }
    for (double e : residuals) cost_before += 0.5 * e * e;
    summary.residuals += residuals.size();
  }
  for (std::size_t r = 0; r < summary.records.size(); ++r)
    for (std::size_t j = 0; j < form.outputs.size(); ++j) {
      bool ok = true;
      summary.records[r].rms_before.emplace_back(form.outputs[j].name, rms_of(record_errors(r, j, ok)));
    }
  for (std::size_t c = 0; c < joins.size(); ++c) {
    std::vector<double> residuals(static_cast<std::size_t>(joins[c]->num_residuals()));
    const double* blocks[3] = {parameters.data(), segments[joined[c].first].state.data(), segments[joined[c].second].state.data()};
    if (joins[c]->Evaluate(blocks, residuals.data(), nullptr))
      for (double e : residuals) cost_before += 0.5 * e * e;
  }
  summary.cost_before = cost_before;
  summary.unknowns = p + segments.size() * form.state_size();

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (auto& seg : segments) problem.AddResidualBlock(seg.cost.get(), nullptr, parameters.data(), seg.state.data());
  for (std::size_t c = 0; c < joins.size(); ++c)
    problem.AddResidualBlock(joins[c].get(), nullptr, parameters.data(), segments[joined[c].first].state.data(),
                             segments[joined[c].second].state.data());
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

  // The Jacobian at the estimate (output rows, then the joins' rows), for the covariance; the
  // output errors' own cost apart, for sigma^2.
  const std::size_t join_rows = joins.size() * form.state_size();
  Eigen::MatrixXd jacobian =
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(summary.residuals + join_rows), static_cast<Eigen::Index>(summary.unknowns));
  Eigen::Index row = 0;
  double output_cost = 0;
  for (std::size_t k = 0; k < segments.size() && jacobian.size() > 0; ++k) {
    const std::size_t m = static_cast<std::size_t>(segments[k].cost->num_residuals()), n = segments[k].cost->state_size();
    std::vector<double> residuals(m), jp(m * p), jx(m * n);
    const double* blocks[2] = {parameters.data(), segments[k].state.data()};
    double* jacobians[2] = {jp.data(), jx.data()};
    if (!segments[k].cost->Evaluate(blocks, residuals.data(), jacobians)) {
      summary.message += "; the estimate's run failed when its Jacobian was evaluated, so no intervals";
      jacobian.resize(0, 0);
      break;
    }
    for (double e : residuals) output_cost += 0.5 * e * e;
    for (std::size_t i = 0; i < m; ++i) {
      for (std::size_t q = 0; q < p; ++q) jacobian(row + static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(q)) = jp[i * p + q];
      for (std::size_t q = 0; q < n; ++q)
        jacobian(row + static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(p + k * n + q)) = jx[i * n + q];
    }
    row += static_cast<Eigen::Index>(m);
  }
  for (std::size_t c = 0; c < joins.size() && jacobian.size() > 0; ++c) {
    const std::size_t n = form.state_size(), from = joined[c].first, to = joined[c].second;
    std::vector<double> residuals(n), j0(n * p), j1(n * n), j2(n * n);
    const double* blocks[3] = {parameters.data(), segments[from].state.data(), segments[to].state.data()};
    double* jacobians[3] = {j0.data(), j1.data(), j2.data()};
    if (!joins[c]->Evaluate(blocks, residuals.data(), jacobians)) {
      jacobian.resize(0, 0);
      break;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Index r = row + static_cast<Eigen::Index>(i);
      for (std::size_t q = 0; q < p; ++q) jacobian(r, static_cast<Eigen::Index>(q)) = j0[i * p + q];
      for (std::size_t q = 0; q < n; ++q) {
        jacobian(r, static_cast<Eigen::Index>(p + from * n + q)) = j1[i * n + q];
        jacobian(r, static_cast<Eigen::Index>(p + to * n + q)) = j2[i * n + q];
      }
    }
    row += static_cast<Eigen::Index>(n);
    summary.largest_defect = std::max(summary.largest_defect, joins[c]->largest_defect(parameters.data(), segments[from].state.data(),
                                                                                       segments[to].state.data(), kContinuityWeight));
  }
  std::vector<std::vector<std::vector<double>>> output_errors(form.outputs.size());  // per output, per record
  for (std::size_t r = 0; r < summary.records.size(); ++r) {
    for (std::size_t j = 0; j < form.outputs.size(); ++j) {
      bool ok = true;
      std::vector<double> e = record_errors(r, j, ok);
      if (!ok) continue;
      summary.records[r].rms_after.emplace_back(form.outputs[j].name, rms_of(e));
      output_errors[j].push_back(std::move(e));
    }
    const auto first = std::find_if(segments.begin(), segments.end(), [&](const Segment& seg) { return seg.record == r; });
    summary.records[r].initial = first->cost->state_map(first->state.data());
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
  // Degrees of freedom: the joins tie each later segment's initial state, so they are those of one
  // initial state per record.
  const std::size_t free = p + summary.records.size() * form.state_size();
  if (jacobian.size() > 0 && summary.residuals > free) {
    const double sigma2 = 2 * output_cost / static_cast<double>(summary.residuals - free);
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
  std::string held;
  for (const auto& q : parameters)
    if (q.nonlinear) held += (held.empty() ? "" : ", ") + q.name;
  if (!held.empty())
    out += fmt::format("  {}: entering nonlinearly, the equation-error column gives the value that fit held it at\n", held);
  if (std::any_of(records.begin(), records.end(), [](const RefinedRecord& r) { return r.segments > 1; }))
    out += fmt::format("  multiple shooting{}: each segment solved from its own initial state, the segments joined by the\n"
                       "  continuity of the whole state (weighted {:g} times a sample's output error); the largest jump left at a join\n"
                       "  is {:.2g} of the noise\n",
                       shooting_reason.empty() ? std::string() : " (" + shooting_reason + ")", kContinuityWeight, largest_defect);
  for (const auto& r : records) {
    out += fmt::format("  {}: from sample {}, {} samples{};", r.path, r.first_sample, r.samples,
                       r.segments > 1 ? fmt::format(" in {} shooting segments", r.segments) : "");
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
