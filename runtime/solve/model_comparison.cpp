#include "runtime/solve/model_comparison.hpp"

#include <algorithm>
#include <cmath>

#include "ir/print.hpp"

namespace sidc {

ModelTotals model_totals(const std::string& name, const ir::Model& model, const FitSummary& summary) {
  ModelTotals t;
  t.name = name;
  t.usable = summary.is_solution_usable();
  for (const auto& g : summary.groups) {
    t.n += g.summary.n, t.p += g.summary.p;
    // Weak rows weighted by their noise covariance (weak_covariance.hpp) are whitened by each model's
    // own metric; their unweighted residuals are what two models' G can compare.
    if (g.weak_weighting.applied)
      for (double r : g.summary.residuals) t.G += r * r;
    else
      t.G += g.summary.G;
  }
  for (const auto& equation : model.equations) t.known += print(equation.known) + "; ";
  return t;
}

ModelComparison compare_models(std::vector<ModelTotals> models) {
  ModelComparison c;
  c.same_rows = std::all_of(models.begin(), models.end(), [&](const ModelTotals& m) { return m.n == models.front().n; });
  c.same_known = std::all_of(models.begin(), models.end(), [&](const ModelTotals& m) { return m.known == models.front().known; });
  double best_g = INFINITY, best_aic = INFINITY, best_bic = INFINITY;
  for (auto& m : models) {
    const double n = static_cast<double>(m.n), k = static_cast<double>(m.p);
    m.aic = n * std::log(m.G / n) + 2 * k, m.bic = n * std::log(m.G / n) + k * std::log(n);
    if (m.usable) best_g = std::min(best_g, m.G), best_aic = std::min(best_aic, m.aic), best_bic = std::min(best_bic, m.bic);
  }
  for (auto& m : models) {
    m.least_G = m.usable && c.same_known && c.same_rows && m.G == best_g;
    m.best_aic = m.usable && c.same_known && m.aic == best_aic;
    m.best_bic = m.usable && c.same_known && m.bic == best_bic;
  }
  c.models = std::move(models);
  return c;
}

}  // namespace sidc
