// The refined instrumental-variable iteration (see instrumental_variables.hpp).
//
// Relies on: design.hpp and weak_design.hpp (rows), validate.hpp (the solution from the first
// sample), fitted_values.hpp (estimates laid out for the derivative form), Eigen (QR) and
// Boost.Math (Student t). Guarantees: the header's.
#include "runtime/solve/instrumental_variables.hpp"

#include "runtime/solve/hac_covariance.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>

#include <Eigen/Dense>
#include <boost/math/distributions/students_t.hpp>
#include <fmt/format.h>

#include "ir/queries.hpp"
#include "runtime/operators/operator_choice.hpp"
#include "runtime/simulate/validate.hpp"
#include "runtime/solve/design.hpp"
#include "runtime/solve/fitted_values.hpp"
#include "runtime/solve/weak_design.hpp"

namespace sidc {

using Index = Eigen::Index;  // as best_subset.cpp and the least-squares files say it

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// One record as the fit evaluated it: its arcs (under savgol(auto), chosen from the record, and
// kept for the instruments, so that both sides see the same operators) and its fit window.
struct RecordPlan {
  EvaluationOptions evaluation;
  FitWindow window;
};

// One group's rows: the fit's regressors Phi (A), known side b and row weights, evaluated once on
// the records; and what the instruments need to be laid out the same way.
struct GroupRows {
  const GroupFit* fitted = nullptr;
  DesignBuilder design;
  bool weak = false;
  MatrixXd A;
  VectorXd b, weights;                  // weights: all 1 when the fit is unweighted
  std::vector<TestFunctionGrid> grids;  // weak form: per record, the subdomains the fit chose from the record
};

// Phi, b and the weights of `g`'s group exactly as fit.cpp lays them out (record by record,
// equation by equation); the problem's message when one cannot be evaluated.
std::optional<std::string> fitted_rows(GroupRows& g, const ir::Model& model, const std::vector<SampledRecord>& records,
                                       const std::vector<RecordPlan>& plans) {
  const auto p = static_cast<Index>(g.design.columns().size());
  std::vector<MatrixXd> A;
  std::vector<VectorXd> b, w;
  for (std::size_t r = 0; r < records.size(); ++r) {
    Evaluator evaluator(records[r], model, plans[r].evaluation, plans[r].window);
    std::vector<double> expression;  // `set weights = <expression>` on the window (eq. 2-1.6)
    if (model.weights) {
      auto values = expression_weights(model, evaluator);
      if (auto* d = std::get_if<Diagnostic>(&values)) return d->message;
      expression = std::get<std::vector<double>>(std::move(values));
    }
    if (g.weak) {
      auto made = weak_record_design(model, records, r, evaluator, g.design, g.fitted->equations, expression);
      if (auto* d = std::get_if<Diagnostic>(&made)) return d->message;
      WeakDesign& part = std::get<WeakDesign>(made);
      A.push_back(std::move(part.A));
      b.push_back(std::move(part.b));
      w.push_back(std::move(part.weights));
      g.grids.push_back(std::move(part.grids.front()));
      continue;
    }
    const auto rows = static_cast<Index>(plans[r].window.size() * g.fitted->equations.size());
    A.push_back(MatrixXd::Zero(rows, p));
    b.emplace_back(rows);
    w.push_back(VectorXd::Ones(rows));
    if (auto problem = g.design.window_rows(r, evaluator, expression, A.back(), b.back(), w.back(), 0)) return problem->message;
  }
  Index total = 0;
  for (const auto& part : b) total += part.size();
  g.A.resize(total, p);
  g.b.resize(total);
  g.weights.resize(total);
  Index row = 0;
  for (std::size_t r = 0; r < A.size(); ++r) {
    const Index n = b[r].size();
    g.A.middleRows(row, n) = A[r];
    g.b.segment(row, n) = b[r];
    g.weights.segment(row, n) = g.fitted->weighted ? w[r] : VectorXd::Ones(n);
    row += n;
  }
  return std::nullopt;
}

// The instruments Z of `g`'s group: its design evaluated on `solved` (the records with their
// outputs replaced by the solution), with the fit's operators, windows and subdomains.
std::optional<std::string> instrument_rows(const GroupRows& g, const ir::Model& model, const std::vector<SampledRecord>& solved,
                                           const std::vector<RecordPlan>& plans, MatrixXd& Z) {
  Z = MatrixXd::Zero(g.A.rows(), g.A.cols());
  VectorXd known(g.A.rows()), weights(g.A.rows());  // the solution's known side and weights are not used
  Index row = 0;
  for (std::size_t r = 0; r < solved.size(); ++r) {
    Evaluator evaluator(solved[r], model, plans[r].evaluation, plans[r].window);
    if (g.weak) {
      WeakValues values(evaluator, g.grids[r]);
      const auto K = static_cast<Index>(g.grids[r].centres.size());
      for (std::size_t e : g.fitted->equations) {
        if (auto problem = g.design.equation_rows(r, e, values, {Z.middleRows(row, K), known.segment(row, K)})) return problem->message;
        row += K;
      }
      continue;
    }
    if (auto problem = g.design.window_rows(r, evaluator, {}, Z, known, weights, row)) return problem->message;
    row += static_cast<Index>(plans[r].window.size() * g.fitted->equations.size());
  }
  return std::nullopt;
}

// Powers of two bringing each column's 2-norm into [0.5, 1) (section 3-2, eq. 3-2.4; exact, as in
// least_squares.cpp); 1 for a zero column.
VectorXd column_scales(const MatrixXd& M) {
  VectorXd s = VectorXd::Ones(M.cols());
  for (Index j = 0; j < M.cols(); ++j) {
    const double norm = M.col(j).norm();
    if (norm > 0 && std::isfinite(norm)) {
      int exponent = 0;
      std::frexp(norm, &exponent);
      s(j) = std::ldexp(1.0, -exponent);
    }
  }
  return s;
}

struct IvSolution {
  std::string problem;  // empty when solved
  VectorXd theta;
  MatrixXd covariance;
  MatrixXd hac_covariance;  // Newey-West (hac_covariance.hpp); empty when not computed, hac_note says why
  std::string hac_note;
  double hac_bandwidth = 0, lag1 = 0, band = 0;  // the IV residuals' lag-1 autocorrelation and its 99% band
  std::size_t n = 0;
  double residual_sd = 0;
};

// The square IV system Z^T W Phi theta = Z^T W b, W = diag(w^2) (each row multiplied by its
// weight, eq. 2-1.6; a zero weight drops the row). Forming Z^T Phi would square nothing but still
// multiply the conditions of Z and Phi; instead Z (weighted, columns scaled) is factored by QR with
// column pivoting, Z P = Q1 R, and since P and R are invertible the system is exactly
// Q1^T Phi theta = Q1^T b: a p x p system M theta = c with M the projection of Phi onto the
// instruments' span, solved by pivoted QR (its rank checked). The covariance
// sigma^2 (Z^T Phi)^-1 (Z^T Z) (Phi^T Z)^-1 is then sigma^2 (M^T M)^-1 (R and P cancel), formed
// from M's own factor like least squares' sigma^2 (R^T R)^-1; sigma^2 = |w (b - Phi theta)|^2 / (n - p).
// With Z = Phi the solution is the least-squares one. Double precision: the record's noise, not
// the arithmetic, limits an IV estimate.
//
// The Newey-West covariance, when `segment_starts` (the first rows of the runs of neighbouring rows)
// is given: (Z^T W^2 Phi)^-1 Omega (Phi^T W^2 Z)^-1 with Omega the long-run covariance of the scores
// w_i^2 e_i z_i (hac_covariance.hpp) and the small-sample factor n / (n - p); Z's column scales cancel.
IvSolution solve_iv(const MatrixXd& A, const VectorXd& b, const MatrixXd& Z, const VectorXd& w, const std::vector<std::string>& names,
                    const std::vector<std::size_t>* segment_starts) {
  IvSolution s;
  const Index p = A.cols();
  std::vector<Index> kept;
  for (Index i = 0; i < A.rows(); ++i)
    if (w(i) != 0.0) kept.push_back(i);
  const auto n = static_cast<Index>(kept.size());
  s.n = kept.size();
  if (n <= p) {
    s.problem = fmt::format("{} rows with non-zero weight for {} parameters", n, p);
    return s;
  }
  MatrixXd Aw(n, p), Zw(n, p);
  VectorXd bw(n);
  for (Index k = 0; k < n; ++k) {
    const Index i = kept[static_cast<std::size_t>(k)];
    Aw.row(k) = w(i) * A.row(i);
    Zw.row(k) = w(i) * Z.row(i);
    bw(k) = w(i) * b(i);
  }
  if (!Zw.allFinite()) {
    s.problem = "an instrument is not a finite number";
    return s;
  }
  const VectorXd sa = column_scales(Aw), sz = column_scales(Zw);
  Aw = Aw * sa.asDiagonal();
  Zw = Zw * sz.asDiagonal();
  const double tolerance = DBL_EPSILON * static_cast<double>(std::max(n, p));  // least_squares.hpp's default
  Eigen::ColPivHouseholderQR<MatrixXd> qz(Zw);
  qz.setThreshold(tolerance);
  if (qz.rank() < p) {
    s.problem = fmt::format("the instrument of `{}` depends on the others",
                            names[static_cast<std::size_t>(qz.colsPermutation().indices()(static_cast<Index>(qz.rank())))]);
    return s;
  }
  MatrixXd projected(n, p + 1);
  projected << Aw, bw;
  projected.applyOnTheLeft(qz.householderQ().adjoint());
  const MatrixXd M = projected.topLeftCorner(p, p);
  const VectorXd c = projected.col(p).head(p);
  Eigen::ColPivHouseholderQR<MatrixXd> qm(M);
  qm.setThreshold(tolerance);
  if (qm.rank() < p) {
    s.problem = fmt::format("the instruments do not determine `{}` (Z^T Phi is singular)",
                            names[static_cast<std::size_t>(qm.colsPermutation().indices()(static_cast<Index>(qm.rank())))]);
    return s;
  }
  const VectorXd u = qm.solve(c);
  s.theta = sa.asDiagonal() * u;
  const double G = (bw - Aw * u).squaredNorm();
  const double variance = G / static_cast<double>(n - p);
  s.residual_sd = std::sqrt(variance);
  // (M^T M)^-1 = P R^-1 R^-T P^T for M P = Q R.
  const MatrixXd R = qm.matrixR().topLeftCorner(p, p).triangularView<Eigen::Upper>();
  const MatrixXd Rinv = R.triangularView<Eigen::Upper>().solve(MatrixXd::Identity(p, p));
  const MatrixXd pivoted = Rinv * Rinv.transpose();
  MatrixXd unpivoted(p, p);
  const auto& perm = qm.colsPermutation().indices();
  for (Index i = 0; i < p; ++i)
    for (Index j = 0; j < p; ++j) unpivoted(perm(i), perm(j)) = pivoted(i, j);
  s.covariance = variance * (sa.asDiagonal() * unpivoted * sa.asDiagonal());
  if (!segment_starts) return s;
  // The kept rows' segments: a run starts where a given segment starts, or after a dropped row.
  std::vector<std::size_t> segment_of(static_cast<std::size_t>(A.rows()), 0);
  for (std::size_t i = 0, id = 0, next = 0; i < segment_of.size(); ++i) {
    while (next < segment_starts->size() && (*segment_starts)[next] <= i) ++id, ++next;
    segment_of[i] = id;
  }
  std::vector<std::size_t> starts;
  for (Index k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(kept[static_cast<std::size_t>(k)]);
    const auto before = k > 0 ? static_cast<std::size_t>(kept[static_cast<std::size_t>(k - 1)]) : i;
    if (k == 0 || before + 1 != i || segment_of[before] != segment_of[i]) starts.push_back(static_cast<std::size_t>(k));
  }
  const VectorXd e = bw - Aw * u;
  s.lag1 = lag1_autocorrelation(std::vector<double>(e.data(), e.data() + e.size()), starts);
  s.band = 2.576 / std::sqrt(static_cast<double>(n));
  const MatrixXd scores = e.asDiagonal() * Zw;
  const LongRunCovariance omega = long_run_covariance(scores, starts);
  s.hac_bandwidth = omega.bandwidth;
  if (!omega.computed) {
    s.hac_note = omega.note;
    return s;
  }
  const MatrixXd bread = (Zw.transpose() * Aw).inverse();  // (Z^T W^2 Phi)^-1, scaled coordinates
  const MatrixXd scaled = static_cast<double>(n) / static_cast<double>(n - p) * (bread * omega.omega * bread.transpose());
  s.hac_covariance = sa.asDiagonal() * scaled * sa.asDiagonal();
  if (!s.hac_covariance.allFinite()) {
    s.hac_covariance.resize(0, 0);
    s.hac_note = "the sandwich is not finite";
  }
  return s;
}

// The derivative form's parameter values for the estimates `theta` of the fit's groups, laid out
// as every solve of the fitted equations lays them out (fitted_values.hpp).
std::vector<double> parameter_values(const ir::Model& normalized, const FitSummary& fitted, const std::vector<VectorXd>& theta) {
  FitSummary estimates;
  for (std::size_t g = 0; g < fitted.groups.size(); ++g) {
    GroupFit group;
    group.summary.parameters = fitted.groups[g].summary.parameters;
    for (std::size_t c = 0; c < group.summary.parameters.size(); ++c) group.summary.parameters[c].value = theta[g](static_cast<Index>(c));
    estimates.groups.push_back(std::move(group));
  }
  return fitted_parameter_values(normalized, estimates, 0.0);
}

// The fitted equations solved from every record (validate.hpp, from the first sample, the initial
// state estimated): the records with their outputs replaced by the solution, and the worst fit %.
struct Solution {
  std::string problem;  // "diverge on `r.csv`: ..." when a run could not be completed
  std::vector<SampledRecord> records;
  double worst_fit_percent = std::numeric_limits<double>::infinity();
};

Solution solve_equations(const ir::Model& normalized, const ExplicitForm& form, const std::vector<double>& parameters,
                         const std::vector<SampledRecord>& records, const EvaluationOptions& evaluation) {
  Solution out;
  ValidationOptions o;
  o.evaluation = evaluation;
  o.max_samples = 0;  // every sample: the instruments cover the whole window
  o.initial_state = InitialState::estimate;
  o.from_first_sample = true;
  for (const auto& record : records) {
    auto run = validate(normalized, form, parameters, record, o);
    if (auto* d = std::get_if<Diagnostic>(&run)) {
      out.problem = fmt::format("cannot be solved on `{}` ({})", record.path, d->message);
      return out;
    }
    const ValidationSummary& v = std::get<ValidationSummary>(run);
    if (!v.simulation.completed()) {
      out.problem = fmt::format("could not be solved over `{}`: {}", record.path, v.simulation.message);
      return out;
    }
    SampledRecord solved = record;
    for (std::size_t j = 0; j < form.outputs.size(); ++j) {
      if (v.simulation.outputs[j].size() != record.time.size()) {
        out.problem = fmt::format("were solved over {} of the {} samples of `{}`", v.simulation.outputs[j].size(), record.time.size(), record.path);
        return out;
      }
      solved.signals[form.outputs[j].name] = v.simulation.outputs[j];
    }
    for (const auto& o2 : v.outputs) out.worst_fit_percent = std::min(out.worst_fit_percent, o2.fit_percent);
    out.records.push_back(std::move(solved));
  }
  return out;
}

double t_quantile(double probability, double degrees_of_freedom) {
  if (!(degrees_of_freedom > 0)) return std::numeric_limits<double>::quiet_NaN();
  return boost::math::quantile(boost::math::students_t_distribution<double>(degrees_of_freedom), probability);
}

}  // namespace

bool InstrumentalVariablesOptions::is_valid(std::string* why) const {
  std::string reason;
  if (max_iterations < 1) reason = fmt::format("max_iterations must be at least 1 (it is {})", max_iterations);
  else if (!(tolerance > 0) || !std::isfinite(tolerance)) reason = fmt::format("tolerance must be a positive number (it is {})", tolerance);
  else if (!(confidence_level > 0 && confidence_level < 1)) reason = fmt::format("confidence_level must lie in (0, 1) (it is {})", confidence_level);
  if (why) *why = reason;
  return reason.empty();
}

const char* to_string(InstrumentalVariablesSummary::Termination termination) {
  switch (termination) {
    case InstrumentalVariablesSummary::Termination::converged: return "converged";
    case InstrumentalVariablesSummary::Termination::max_iterations: return "max_iterations";
    case InstrumentalVariablesSummary::Termination::stopped: return "stopped";
    case InstrumentalVariablesSummary::Termination::not_started: return "not_started";
  }
  return "not_started";
}

bool InstrumentalVariablesSummary::is_solution_usable() const { return termination == Termination::converged; }

std::string InstrumentalVariablesSummary::brief_report() const {
  std::string out = fmt::format("instrumental variables: {}, {} iteration{}", to_string(termination), iterations, iterations == 1 ? "" : "s");
  if (!changes.empty()) out += fmt::format(", last change {:.2g}", changes.back());
  if (fit_percent && equation_error_fit_percent)
    out += fmt::format(", solved: fit {:.4g}% (equation error {:.4g}%)", *fit_percent, *equation_error_fit_percent);
  return out;
}

std::string InstrumentalVariablesSummary::full_report() const {
  std::string out = fmt::format("Instrumental variables (refined, {} iteration{}): {}\n", iterations, iterations == 1 ? "" : "s", statement);
  if (groups.empty()) return out;
  out += "  instruments: each operation evaluated, with the fit's operators, rows and weights, on the fitted equations solved\n"
         "  from the record (noise-free); Young & Jakeman's refined instrumental variables (SRIVC)\n";
  if (!changes.empty()) {
    std::string listed;
    for (double c : changes) listed += fmt::format("{}{:.2g}", listed.empty() ? "" : ", ", c);
    out += fmt::format("  largest relative change per iteration: {} (tolerance {:g})\n", listed, tolerance);
  }
  const bool units = std::any_of(groups.begin(), groups.end(), [](const auto& g) {
    return std::any_of(g.parameters.begin(), g.parameters.end(), [](const auto& p) { return !p.unit.empty(); });
  });
  out += fmt::format("  {:<14} {:>15} {:>13}   {:>31}   {:>15}{}\n", "parameter", "IV estimate", "std. error", "95% confidence interval",
                     "equation error", units ? "   unit" : "");
  for (const auto& g : groups)
    for (const auto& p : g.parameters)
      out += fmt::format("  {:<14} {:>15.6g} {:>13.4g}   [{:>13.6g}, {:>13.6g}]   {:>15.6g}{}\n", p.name, p.value, p.standard_error, p.ci_low,
                         p.ci_high, p.equation_error, p.unit.empty() ? "" : "   " + p.unit);
  for (std::size_t g = 0; g < groups.size(); ++g)
    out += fmt::format("  {}n = {}, p = {}, residual s.d. of the IV residuals b - Phi theta = {:.4g}\n",
                       groups.size() > 1 ? fmt::format("group {}: ", g + 1) : std::string(), groups[g].n, groups[g].p, groups[g].residual_sd);
  // The intervals above treat the rows as independent; the Newey-West ones allow for autocorrelated
  // rows, and the IV residuals' lag-1 autocorrelation says which to trust (docs/accuracy.md).
  const auto has = [&](const char* form) { return std::any_of(groups.begin(), groups.end(), [&](const auto& g) { return g.form == form; }); };
  for (std::size_t gi = 0; gi < groups.size() && iterations > 0; ++gi) {
    const auto& g = groups[gi];
    const std::string which = groups.size() > 1 ? fmt::format(" (group {})", gi + 1) : std::string();
    if (!g.hac) {
      if (!g.hac_note.empty()) out += fmt::format("  Newey-West (HAC) intervals{}: not computed: {}\n", which, g.hac_note);
      continue;
    }
    const bool correlated = std::abs(g.lag1) > g.band;
    out += fmt::format("  Newey-West (HAC) intervals{}, which allow for autocorrelated rows (Bartlett kernel of bandwidth {:.1f} rows);\n"
                       "  the IV residuals' lag-1 autocorrelation is {:.3g}, {} the 99% band +-{:.2g} of independent rows:\n  {}\n",
                       which, g.hac_bandwidth, g.lag1, correlated ? "outside" : "inside", g.band,
                       correlated ? "the intervals above are too narrow, trust these" : "the intervals above hold their assumption");
    out += fmt::format("  {:<14} {:>15}   {:>31}   {}\n", "parameter", "HAC std. error", "95% confidence interval", "x IV's");
    for (const auto& p : g.parameters)
      out += fmt::format("  {:<14} {:>15.4g}   [{:>13.6g}, {:>13.6g}]   {:.3g}\n", p.name, p.hac_standard_error, p.hac_ci_low, p.hac_ci_high,
                         p.standard_error > 0 ? p.hac_standard_error / p.standard_error : std::numeric_limits<double>::quiet_NaN());
  }
  if (iterations > 0 && has("weak"))
    out += "  (neighbouring subdomains overlap, so the rows are not independent; these intervals held the truth for 89-96% of the\n"
           "  parameters of known-truth records (docs/accuracy.md))\n";
  if (fit_percent && equation_error_fit_percent)
    out += fmt::format("  the equations solved from the records (worst output and record): fit {:.4g}% with {}, {:.4g}% with the "
                       "equation-error estimate\n",
                       *fit_percent, iterations > 0 ? "this estimate" : "it", *equation_error_fit_percent);
  return out;
}

InstrumentalVariablesSummary instrumental_variables(const ir::Model& model, const ir::Model& normalized,
                                                    const std::variant<ExplicitForm, Diagnostic>& form,
                                                    const std::vector<SampledRecord>& records, const FitOptions& options,
                                                    const FitSummary& fitted, const InstrumentalVariablesOptions& iv_options) {
  using Termination = InstrumentalVariablesSummary::Termination;
  InstrumentalVariablesSummary s;
  s.max_iterations = iv_options.max_iterations;
  s.tolerance = iv_options.tolerance;
  const auto not_started = [&s](const std::string& why) {
    s.termination = Termination::not_started;
    s.statement = "not started: " + why + "; the equation-error estimate stands.";
    return s;
  };
  if (std::string why; !iv_options.is_valid(&why)) return not_started("invalid options, " + why);
  if (const auto* d = std::get_if<Diagnostic>(&form))
    return not_started("the equations cannot be solved for their highest derivatives (" + d->message +
                       "), so there is no noise-free solution to take instruments from");
  if (!fitted.is_solution_usable()) return not_started("the equation-error fit is rank deficient");
  if (fitted.operators.size() != records.size()) return not_started("the fit does not belong to these records");
  for (std::size_t g = 0; g < fitted.groups.size(); ++g)
    if (!fitted.groups[g].streamed.empty())
      return not_started(fmt::format("the design of equation {} is streamed ({}); the instruments need it in memory",
                                     fitted.groups[g].equations.front() + 1, fitted.groups[g].streamed));
  const ExplicitForm& explicit_form = std::get<ExplicitForm>(form);

  std::vector<RecordPlan> plans;
  for (std::size_t r = 0; r < records.size(); ++r) {
    RecordPlan plan{with_arcs(options.evaluation, fitted.operators[r]), {}};
    auto window = fit_window(records[r], model, plan.evaluation, options.from, options.to);
    if (auto* d = std::get_if<Diagnostic>(&window)) return not_started(d->message);
    plan.window = std::get<FitWindow>(window);
    plans.push_back(std::move(plan));
  }
  std::vector<GroupRows> groups;
  groups.reserve(fitted.groups.size());
  for (const auto& g : fitted.groups) {
    auto weak = is_weak_group(model, g.equations);
    if (auto* d = std::get_if<Diagnostic>(&weak)) return not_started(d->message);
    groups.push_back(GroupRows{&g, DesignBuilder(model, records, g.equations), std::get<bool>(weak), {}, {}, {}, {}});
    if (auto problem = fitted_rows(groups.back(), model, records, plans)) return not_started(*problem);
    if (groups.back().A.cols() != static_cast<Index>(g.summary.parameters.size()) || groups.back().b.size() == 0)
      return not_started("the design does not match the fit");
  }

  // The iteration. current: the estimate whose equations are solved next; solutions: the IV solves
  // behind it (none for the equation-error estimate); previous: the estimate before it.
  std::vector<VectorXd> current, previous;
  for (const auto& g : fitted.groups) {
    VectorXd theta(static_cast<Index>(g.summary.parameters.size()));
    for (std::size_t c = 0; c < g.summary.parameters.size(); ++c) theta(static_cast<Index>(c)) = g.summary.parameters[c].value;
    current.push_back(std::move(theta));
  }
  std::vector<IvSolution> solutions, previous_solutions;
  std::optional<double> previous_fit;
  int k = 0;  // IV solves behind `current`
  for (;;) {
    Solution solved = solve_equations(normalized, explicit_form, parameter_values(normalized, fitted, current), records, options.evaluation);
    if (!solved.problem.empty()) {
      if (k == 0)
        return not_started("the equations with the equation-error estimate " + solved.problem +
                           ", so there is no noise-free solution to take instruments from");
      s.termination = Termination::stopped;
      s.statement = fmt::format("stopped: the equations with the estimate of iteration {} {}; {} is kept", k, solved.problem,
                                k == 1 ? "the equation-error estimate, whose equations could be solved,"
                                       : fmt::format("the estimate of iteration {}, whose equations could be solved,", k - 1));
      current = std::move(previous);
      solutions = std::move(previous_solutions);
      s.fit_percent = previous_fit;
      --k;
      break;
    }
    if (k == 0) s.equation_error_fit_percent = solved.worst_fit_percent;
    s.fit_percent = solved.worst_fit_percent;
    if (k > 0 && s.changes.back() < iv_options.tolerance) {
      s.termination = Termination::converged;
      s.statement = fmt::format("converged: the last iteration moved no parameter by more than {:.2g} of itself (tolerance {:g})",
                                s.changes.back(), iv_options.tolerance);
      break;
    }
    if (k == iv_options.max_iterations) {
      s.termination = Termination::max_iterations;
      s.statement = fmt::format("not converged in {} iterations: the last moved a parameter by {:.2g} of itself (tolerance {:g}); its "
                                "estimate is kept",
                                k, s.changes.back(), iv_options.tolerance);
      break;
    }
    // The instruments from this solution, and the next estimate.
    std::vector<VectorXd> next;
    std::vector<IvSolution> next_solutions;
    std::string problem;
    for (std::size_t g = 0; g < groups.size() && problem.empty(); ++g) {
      MatrixXd Z;
      if (auto bad = instrument_rows(groups[g], model, solved.records, plans, Z)) {
        problem = "its instruments could not be evaluated: " + *bad;
        break;
      }
      // Neighbouring rows (one record's window of one equation) for the Newey-West intervals; not
      // for the weak form, whose rows are overlapping subdomains (docs/accuracy.md).
      const GroupFit& fg = fitted.groups[g];
      const std::vector<std::size_t> segments = neighbour_runs(fg);
      const bool with_hac = !groups[g].weak && fg.row_record.size() == static_cast<std::size_t>(groups[g].A.rows());
      IvSolution solution = solve_iv(groups[g].A, groups[g].b, Z, groups[g].weights, fitted.groups[g].columns, with_hac ? &segments : nullptr);
      if (!solution.problem.empty()) {
        problem = solution.problem;
        break;
      }
      next.push_back(solution.theta);
      next_solutions.push_back(std::move(solution));
    }
    if (!problem.empty()) {
      s.termination = Termination::stopped;
      s.statement = fmt::format("stopped at iteration {}: {}; {} is kept", k + 1, problem,
                                k == 0 ? "the equation-error estimate" : fmt::format("the estimate of iteration {}", k));
      break;
    }
    double change = 0;
    for (std::size_t g = 0; g < groups.size(); ++g)
      for (Index c = 0; c < next[g].size(); ++c) {
        const double se = fitted.groups[g].summary.parameters[static_cast<std::size_t>(c)].standard_error;
        const double scale = std::max({std::abs(next[g](c)), std::isfinite(se) ? se : 0.0, DBL_MIN});
        change = std::max(change, std::abs(next[g](c) - current[g](c)) / scale);
      }
    s.changes.push_back(change);
    previous = std::move(current);
    previous_solutions = std::move(solutions);
    previous_fit = s.fit_percent;
    current = std::move(next);
    solutions = std::move(next_solutions);
    ++k;
  }
  s.iterations = k;

  // The kept estimate, its intervals, the equation-error estimate beside it.
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const LeastSquaresSummary& ee = fitted.groups[g].summary;
    InstrumentalVariablesGroup out;
    const auto& equations = fitted.groups[g].equations;
    out.form = groups[g].weak ? "weak"
               : std::any_of(equations.begin(), equations.end(), [&](std::size_t e) { return model.equations[e].integrations > 0; })
                   ? "integrated"
                   : "derivative";
    out.p = ee.parameters.size();
    out.n = k > 0 ? solutions[g].n : ee.n;
    out.residual_sd = k > 0 ? solutions[g].residual_sd : ee.residual_sd;
    const double t = t_quantile(0.5 + iv_options.confidence_level / 2, static_cast<double>(out.n) - static_cast<double>(out.p));
    for (std::size_t c = 0; c < ee.parameters.size(); ++c) {
      const ParameterEstimate& e = ee.parameters[c];
      InstrumentalVariablesParameter p;
      p.name = e.name;
      p.index = e.index;
      p.value = p.equation_error = e.value;
      p.standard_error = e.standard_error;
      p.ci_low = e.ci_low;
      p.ci_high = e.ci_high;
      p.unit = parameter_unit(model, e.name);
      if (k > 0) {
        const auto i = static_cast<Index>(c);
        p.value = current[g](i);
        const double variance = solutions[g].covariance(i, i);
        p.standard_error = variance >= 0 ? std::sqrt(variance) : std::numeric_limits<double>::quiet_NaN();
        p.ci_low = p.value - t * p.standard_error;
        p.ci_high = p.value + t * p.standard_error;
        if (solutions[g].hac_covariance.size() > 0) {
          p.hac_standard_error = std::sqrt(std::max(0.0, solutions[g].hac_covariance(i, i)));
          p.hac_ci_low = p.value - t * p.hac_standard_error;
          p.hac_ci_high = p.value + t * p.hac_standard_error;
        }
      }
      out.parameters.push_back(std::move(p));
    }
    if (k > 0) {
      out.hac = solutions[g].hac_covariance.size() > 0;
      out.hac_bandwidth = solutions[g].hac_bandwidth;
      out.lag1 = solutions[g].lag1;
      out.band = solutions[g].band;
      out.hac_note = groups[g].weak ? "" : solutions[g].hac_note;
    }
    s.groups.push_back(std::move(out));
  }
  return s;
}

std::vector<double> instrumental_parameter_values(const ir::Model& normalized, const InstrumentalVariablesSummary& iv,
                                                  std::vector<double> fallback) {
  fallback.resize(normalized.parameters.size(), 0.0);
  for (const auto& g : iv.groups)
    for (const auto& p : g.parameters)
      if (p.index && !p.index->record && p.index->parameter < fallback.size() && normalized.parameters[p.index->parameter].name == p.name)
        fallback[p.index->parameter] = p.value;
  return fallback;
}

}  // namespace sidc
