#include "runtime/solve/variable_projection.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>

#include "ir/fix_parameters.hpp"

namespace sidc {
namespace {

constexpr double kInfinite = std::numeric_limits<double>::infinity();

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
    double total = 0;
    for (const auto& g : s.groups) total += g.summary.G;
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
// 1/2, shrink 1/2) from `start`, first simplex steps `step`; `best` and `best_value` updated in place.
void nelder_mead(Objective& f, std::vector<double>& best, double& best_value, const std::vector<double>& step) {
  const std::size_t m = best.size();
  std::vector<std::vector<double>> x{best};
  std::vector<double> fx{best_value};
  for (std::size_t k = 0; k < m; ++k) {
    auto v = best;
    v[k] += step[k];
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
      return v;
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
  Objective f(model, records, options, nonlinear, projection.max_fits);
  auto at_guess = f(out.guesses);
  if (auto* d = std::get_if<Diagnostic>(&at_guess)) return *d;
  out.G_guess = std::get<double>(at_guess);
  std::vector<double> best = out.guesses;
  double best_value = out.G_guess;
  // The scan, one parameter at a time from the best point so far: a guess may be off by a factor,
  // and G is often multimodal in a frequency or a rate (sin(L*theta), exp(-k*t)).
  for (std::size_t k = 0; k < best.size(); ++k) {
    std::vector<double> scales;
    for (int e = -6; e <= 6; ++e)
      if (e != 0) scales.push_back(std::pow(2.0, e / 2.0));
    for (const double s : scales)
      for (const double sign : {1.0, -1.0}) {
        if (best[k] != 0 && sign < 0) continue;  // a nonzero guess gives the sign
        auto v = best;
        v[k] = best[k] != 0 ? out.guesses[k] * s : sign * s;
        const double g = f.value(v);
        if (g < best_value) best_value = g, best = v;
      }
  }
  std::vector<double> step(best.size());
  for (std::size_t k = 0; k < best.size(); ++k) step[k] = best[k] != 0 ? 0.1 * std::abs(best[k]) : 0.1;
  if (std::isfinite(best_value)) nelder_mead(f, best, best_value, step);
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
  if (!moved())
    return fmt::format("Nonlinear parameters held at their initial guess{}: {} (no value scanned from 1/8 to 8 times it, nor Nelder-Mead,\n"
                       "gave a smaller G; {} fits).\n",
                       names.size() > 1 ? "es" : "", values_text, fits);
  return fmt::format("Nonlinear parameters by variable projection (the linear ones solved for each trial value; {} fits):\n"
                     "  {}, from the guess{} {}: G = {:.6g} there, {:.6g} at the guess{}. The fit above holds them at these values.\n",
                     fits, values_text, names.size() > 1 ? "es" : "", guesses_text, G_best, G_guess, names.size() > 1 ? "es" : "");
}

}  // namespace sidc
