#include "runtime/solve/variable_projection.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <optional>

#include "ir/fix_parameters.hpp"
#include "ir/queries.hpp"
#include "ir/traversal.hpp"

namespace sidc {
namespace {

constexpr double kInfinite = std::numeric_limits<double>::infinity();

// `options` with the weak form's rows unweighted: G is compared between trial values, and rows
// whitened by their noise covariance (weak_covariance.hpp) would change their metric with each.
FitOptions unweighted(FitOptions options) {
  options.weak_covariance = false;
  return options;
}

// eq. 2-1.7 summed over the equation groups.
double total_G(const FitSummary& s) {
  double total = 0;
  for (const auto& g : s.groups) total += g.summary.G;
  return total;
}

// Total G of the linear fit with the nonlinear parameters at `values` (infinite when it cannot be
// fitted or is rank deficient: such a point is never the best).
class Objective {
 public:
  Objective(const ir::Model& model, const std::vector<SampledRecord>& records, const FitOptions& options, std::vector<std::size_t> nonlinear,
            int limit)
      : model_(model), records_(records), options_(options), nonlinear_(std::move(nonlinear)), limit_(limit) {}

  std::variant<double, Diagnostic> operator()(const std::vector<double>& values) {
    ++fits;
    std::vector<double> held(model_.parameters.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t k = 0; k < nonlinear_.size(); ++k) held[nonlinear_[k]] = values[k];
    auto result = fit(fix_nonlinear(model_, held), records_, options_);
    if (auto* d = std::get_if<Diagnostic>(&result)) return *d;
    const FitSummary& s = std::get<FitSummary>(result);
    if (!s.is_solution_usable()) return kInfinite;
    const double total = total_G(s);
    return std::isfinite(total) ? total : kInfinite;
  }
  // Infinite once the budget of fits is spent: the search then ends with the best point so far.
  double value(const std::vector<double>& values) {
    if (fits >= limit_) return kInfinite;
    auto v = (*this)(values);
    return std::holds_alternative<double>(v) ? std::get<double>(v) : kInfinite;
  }
  int fits = 0;

 private:
  const ir::Model& model_;
  const std::vector<SampledRecord>& records_;
  const FitOptions& options_;
  std::vector<std::size_t> nonlinear_;
  int limit_ = 0;
};

// Nelder-Mead (Lagarias et al., SIAM J. Optim. 9(1), 1998: reflection 1, expansion 2, contraction
// 1/2, shrink 1/2) from `best`, first simplex steps `step`, every point kept within [low, high];
// `best` and `best_value` updated in place.
void nelder_mead(Objective& f, std::vector<double>& best, double& best_value, const std::vector<double>& step, const std::vector<double>& low,
                 const std::vector<double>& high) {
  const std::size_t m = best.size();
  const auto inside = [&](std::vector<double> v) {
    for (std::size_t i = 0; i < m; ++i) v[i] = std::clamp(v[i], low[i], high[i]);
    return v;
  };
  std::vector<std::vector<double>> x{best};
  std::vector<double> fx{best_value};
  for (std::size_t k = 0; k < m; ++k) {
    auto v = best;
    v[k] += v[k] + step[k] <= high[k] ? step[k] : -step[k];
    v = inside(v);
    x.push_back(v);
    fx.push_back(f.value(v));
  }
  while (true) {
    std::vector<std::size_t> order(m + 1);
    for (std::size_t k = 0; k <= m; ++k) order[k] = k;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return fx[a] < fx[b]; });
    const std::size_t lo = order.front(), hi = order.back(), next = order[m - 1];  // next: the second worst
    // Converged: the values agree to 1e-10 of G, or the simplex has shrunk to 1e-9 of the point.
    double size = 0, scale = 0;
    for (std::size_t k = 0; k <= m; ++k)
      for (std::size_t i = 0; i < m; ++i) size = std::max(size, std::abs(x[k][i] - x[lo][i])), scale = std::max(scale, std::abs(x[lo][i]));
    if (!std::isfinite(fx[lo]) || (std::isfinite(fx[hi]) && std::abs(fx[hi] - fx[lo]) <= 1e-10 * std::abs(fx[lo])) || size <= 1e-9 * std::max(scale, 1e-12))
      break;
    std::vector<double> centre(m, 0.0);
    for (std::size_t k = 0; k <= m; ++k)
      if (k != hi)
        for (std::size_t i = 0; i < m; ++i) centre[i] += x[k][i] / static_cast<double>(m);
    const auto along = [&](double t) {
      std::vector<double> v(m);
      for (std::size_t i = 0; i < m; ++i) v[i] = centre[i] + t * (x[hi][i] - centre[i]);
      return inside(v);
    };
    auto r = along(-1.0);
    const double fr = f.value(r);
    if (fr < fx[lo]) {
      auto e = along(-2.0);
      const double fe = f.value(e);
      if (fe < fr) x[hi] = e, fx[hi] = fe;
      else x[hi] = r, fx[hi] = fr;
    } else if (fr < fx[next]) {
      x[hi] = r, fx[hi] = fr;
    } else {
      auto c = fr < fx[hi] ? along(-0.5) : along(0.5);
      const double fc = f.value(c);
      if (fc < std::min(fr, fx[hi])) {
        x[hi] = c, fx[hi] = fc;
      } else {  // shrink toward the best
        for (std::size_t k = 0; k <= m; ++k) {
          if (k == lo) continue;
          for (std::size_t i = 0; i < m; ++i) x[k][i] = x[lo][i] + 0.5 * (x[k][i] - x[lo][i]);
          fx[k] = f.value(x[k]);
        }
      }
    }
  }
  for (std::size_t k = 0; k <= m; ++k)
    if (fx[k] < best_value) best = x[k], best_value = fx[k];
}

// The first nonlinear parameter that stands in a guard or in sign() (a threshold, `[y > y0]`): G
// changes in steps as the threshold passes samples (in the weak form, whose switches are located
// between the samples, its slope does), so it has no curvature to take there.
const ir::Parameter* threshold(const ir::Model& model) {
  const ir::Parameter* found = nullptr;
  const auto visit = [&](const ir::Factor& f, const ir::Term&) {
    if (is_switch(f))
      ir::for_each_nested_sum(f, [&](const ir::Sum& inner) {
        ir::for_each_factor(inner, [&](const ir::Factor& g) {
          if (g.kind == ir::FactorKind::parameter && !found) found = &model.parameters[static_cast<std::size_t>(g.order)];
        });
      });
    return found ? ir::Step::stop : ir::Step::into;
  };
  for (const auto& e : model.equations) {
    for (const auto& t : e.terms) ir::walk_factors(t.operation, visit);
    ir::walk_factors(e.known, visit);
  }
  return found;
}

}  // namespace

std::variant<VariableProjectionSummary, Diagnostic> variable_projection(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                                        const FitOptions& options, const VariableProjectionOptions& projection) {
  VariableProjectionSummary out;
  std::vector<std::size_t> nonlinear;
  for (std::size_t k = 0; k < model.parameters.size(); ++k) {
    const ir::Parameter& p = model.parameters[k];
    if (!p.nonlinear) continue;
    nonlinear.push_back(k);
    out.names.push_back(p.name);
    out.guesses.push_back(p.guess ? p.guess->value() : 0.0);
  }
  const FitOptions searched = unweighted(options);  // Objective keeps a reference
  Objective f(model, records, searched, nonlinear, projection.max_fits);
  auto at_guess = f(out.guesses);
  if (auto* d = std::get_if<Diagnostic>(&at_guess)) return *d;
  out.G_guess = std::get<double>(at_guess);
  std::vector<double> best = out.guesses;
  double best_value = out.G_guess;
  // The scan, one parameter at a time from the best point so far: a guess may be off by a factor,
  // and G is often multimodal in a frequency or a rate (sin(L*theta), exp(-k*t)).
  for (std::size_t k = 0; k < best.size(); ++k) {
    const double guess = out.guesses[k];
    std::vector<double> scales;
    for (int e = -6; e <= 6; ++e)
      if (e != 0) scales.push_back(std::pow(2.0, e / 2.0));
    for (const double s : scales)
      for (const double sign : {1.0, -1.0}) {
        if (guess != 0 && sign < 0) continue;  // a nonzero guess gives the sign
        auto v = best;
        v[k] = guess != 0 ? guess * s : sign * s;
        const double g = f.value(v);
        if (g < best_value) best_value = g, best = v;
      }
  }
  // The search stays within the scanned range: beyond it a value is rather a sign that the data do not
  // determine the parameter (sin(L*y) beside a*y, as L goes to 0) than an estimate.
  std::vector<double> step(best.size()), low(best.size()), high(best.size());
  for (std::size_t k = 0; k < best.size(); ++k) {
    step[k] = best[k] != 0 ? 0.1 * std::abs(best[k]) : 0.1;
    const double g = out.guesses[k];
    low[k] = g > 0 ? g / 8 : g < 0 ? 8 * g : -8.0;
    high[k] = g > 0 ? 8 * g : g < 0 ? g / 8 : 8.0;
  }
  if (std::isfinite(best_value)) nelder_mead(f, best, best_value, step, low, high);
  for (std::size_t k = 0; k < best.size(); ++k)
    if (std::abs(best[k] - low[k]) <= 1e-6 * std::abs(low[k]) || std::abs(best[k] - high[k]) <= 1e-6 * std::abs(high[k]))
      out.at_edge.push_back(out.names[k]);
  out.values = best;
  out.G_best = best_value;
  out.fits = f.fits;
  out.held.assign(model.parameters.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < nonlinear.size(); ++k) out.held[nonlinear[k]] = out.values[k];
  return out;
}

std::string VariableProjectionSummary::report() const {
  std::string values_text, guesses_text;
  for (std::size_t k = 0; k < names.size(); ++k) {
    values_text += fmt::format("{}{} = {:.7g}", k ? ", " : "", names[k], values[k]);
    guesses_text += fmt::format("{}{:.7g}", k ? ", " : "", guesses[k]);
  }
  if (!std::isfinite(G_best))
    return fmt::format("Nonlinear parameters: no value near the initial guess{} ({}) gives a usable equation-error fit ({} fits tried);\n"
                       "the fit above holds them at the guess{}.\n",
                       names.size() > 1 ? "es" : "", guesses_text, fits, names.size() > 1 ? "es" : "");
  std::string edge;
  for (const auto& name : at_edge) edge += (edge.empty() ? "" : ", ") + name;
  std::string errors;
  for (std::size_t k = 0; k < standard_errors.size() && k < names.size(); ++k)
    if (std::isfinite(standard_errors[k])) errors += fmt::format("{}{} {:.3g}", errors.empty() ? "" : ", ", names[k], standard_errors[k]);
  if (!errors.empty())
    errors = fmt::format("  Standard error{} {} (from the curvature of G over {}); the classical intervals above include {}\n"
                         "  uncertainty (the Newey-West ones, where printed, do not) and, like them, assume independent rows.\n",
                         names.size() > 1 ? "s:" : " of", errors, names.size() > 1 ? "them" : "it", names.size() > 1 ? "their" : "its");
  else if (!interval_note.empty())
    errors = "  No standard error: " + interval_note + ";\n  the intervals above are those with the held values taken as known.\n";
  if (!edge.empty())
    edge = fmt::format("  {} ended at the edge of the range searched (1/8 to 8 times the guess): the data may not determine {} (G keeps\n"
                       "  falling beyond it, as when a parameter's operation approaches another candidate's), or the guess is far off.\n",
                       edge, at_edge.size() > 1 ? "them" : "it");
  if (!moved())
    return fmt::format("Nonlinear parameters held at their initial guess{}: {} (no value scanned from 1/8 to 8 times it, nor Nelder-Mead,\n"
                       "gave a smaller G; {} fits).\n",
                       names.size() > 1 ? "es" : "", values_text, fits) +
           errors + edge;
  return fmt::format("Nonlinear parameters by variable projection (the linear ones solved for each trial value; {} fits):\n"
                     "  {}, from the guess{} {}: G = {:.6g} there, {:.6g} at the guess{}. The fit above holds {} at {}.\n",
                     fits, values_text, names.size() > 1 ? "es" : "", guesses_text, G_best, G_guess, names.size() > 1 ? "es" : "",
                     names.size() > 1 ? "them" : "it", names.size() > 1 ? "these values" : "this value") +
         errors + edge;
}

NonlinearIntervals nonlinear_intervals(const ir::Model& model, const std::vector<SampledRecord>& records, const FitOptions& options,
                                       const std::vector<double>& held, FitSummary& summary) {
  NonlinearIntervals out;
  std::vector<std::size_t> nonlinear;
  for (std::size_t k = 0; k < model.parameters.size(); ++k)
    if (model.parameters[k].nonlinear) nonlinear.push_back(k);
  const std::size_t m = nonlinear.size();
  out.standard_errors.assign(m, std::numeric_limits<double>::quiet_NaN());
  if (!summary.is_solution_usable()) {
    out.note = "the fit is rank deficient";
    return out;
  }
  if (const ir::Parameter* p = threshold(model)) {
    out.note = fmt::format("`{}` is a threshold (in a guard or sign()), where G, or in the weak form its slope, changes in steps as it passes the samples", p->name);
    return out;
  }
  const double G = total_G(summary);
  std::size_t rows = 0, rank = 0;
  for (const auto& g : summary.groups) rows += g.summary.n, rank += g.summary.rank;
  if (rows <= rank + m) {
    out.note = "too few rows for the nonlinear parameters' curvature";
    return out;
  }
  // The fit with the nonlinear parameters moved by `shift` (per nonlinear parameter).
  const FitOptions as_searched = unweighted(options);
  const auto fitted_at = [&](const std::vector<double>& shift) -> std::optional<FitSummary> {
    std::vector<double> values = held;
    for (std::size_t k = 0; k < m; ++k) values[nonlinear[k]] += shift[k];
    auto r = fit(fix_nonlinear(model, values), records, as_searched);
    if (auto* s = std::get_if<FitSummary>(&r); s && s->is_solution_usable()) return std::move(*s);
    return std::nullopt;
  };
  std::vector<double> h(m);
  for (std::size_t k = 0; k < m; ++k) h[k] = 1e-3 * std::max(std::abs(held[nonlinear[k]]), 1e-6);
  // The profile's Hessian, and the linear solution's derivatives, per group and column.
  Eigen::MatrixXd hessian(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
  std::vector<std::vector<std::vector<double>>> moved(m);  // [k][group][column]: da/dk
  for (std::size_t k = 0; k < m; ++k) {
    std::vector<double> up(m, 0.0), down(m, 0.0);
    up[k] = h[k], down[k] = -h[k];
    const auto plus = fitted_at(up), minus = fitted_at(down);
    if (!plus || !minus || plus->groups.size() != summary.groups.size() || minus->groups.size() != summary.groups.size()) {
      out.note = "a fit next to the held values failed";
      return out;
    }
    hessian(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k)) = (total_G(*plus) - 2 * G + total_G(*minus)) / (h[k] * h[k]);
    moved[k].resize(summary.groups.size());
    for (std::size_t g = 0; g < summary.groups.size(); ++g) {
      const auto& a = plus->groups[g].summary.parameters;
      const auto& b = minus->groups[g].summary.parameters;
      if (a.size() != summary.groups[g].summary.parameters.size() || b.size() != a.size()) {
        out.note = "a fit next to the held values has other columns";
        return out;
      }
      for (std::size_t c = 0; c < a.size(); ++c) moved[k][g].push_back((a[c].value - b[c].value) / (2 * h[k]));
    }
    for (std::size_t j = 0; j < k; ++j) {
      double corners = 0;
      for (const double sj : {1.0, -1.0})
        for (const double sk : {1.0, -1.0}) {
          std::vector<double> shift(m, 0.0);
          shift[j] = sj * h[j], shift[k] = sk * h[k];
          const auto at = fitted_at(shift);
          if (!at) {
            out.note = "a fit next to the held values failed";
            return out;
          }
          corners += sj * sk * total_G(*at);
        }
      const double cross = corners / (4 * h[j] * h[k]);
      hessian(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(k)) = cross;
      hessian(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j)) = cross;
    }
  }
  Eigen::LLT<Eigen::MatrixXd> llt(hessian);
  if (llt.info() != Eigen::Success || !hessian.allFinite()) {
    out.note = "G is not curved upward at the held values (the data do not determine them)";
    return out;
  }
  const double s2 = G / static_cast<double>(rows - rank - m);
  const Eigen::MatrixXd cov = 2 * s2 * llt.solve(Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m)));
  for (std::size_t k = 0; k < m; ++k) out.standard_errors[k] = std::sqrt(cov(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k)));
  // The linear parameters: their conditional covariance plus D Cov(k) D^T, D the columns' da/dk.
  for (std::size_t g = 0; g < summary.groups.size(); ++g) {
    LeastSquaresSummary& ls = summary.groups[g].summary;
    const auto p = static_cast<Eigen::Index>(ls.parameters.size());
    Eigen::MatrixXd d(p, static_cast<Eigen::Index>(m));
    for (Eigen::Index c = 0; c < p; ++c)
      for (std::size_t k = 0; k < m; ++k) d(c, static_cast<Eigen::Index>(k)) = moved[k][g][static_cast<std::size_t>(c)];
    const Eigen::MatrixXd added = d * cov * d.transpose();
    if (ls.covariance.rows() == p && ls.covariance.cols() == p) ls.covariance += added;
    for (Eigen::Index c = 0; c < p; ++c) {
      ParameterEstimate& e = ls.parameters[static_cast<std::size_t>(c)];
      if (!(e.standard_error > 0)) continue;
      const double t = (e.ci_high - e.value) / e.standard_error;  // the interval's quantile, kept
      e.standard_error = std::sqrt(e.standard_error * e.standard_error + added(c, c));
      e.ci_low = e.value - t * e.standard_error;
      e.ci_high = e.value + t * e.standard_error;
    }
  }
  return out;
}

}  // namespace sidc
