// STLSQ on a triangle (see sequential_threshold.hpp).
//
// Relies on: solve_subset (column-pivoted QR of the chosen columns of R, power-of-two scaled).
// Guarantees: the header's.
#include "runtime/select/sequential_threshold.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Core>
#include <fmt/format.h>

namespace sidc {

bool SequentialThresholdOptions::is_valid(int p, std::string* why) const {
  BestSubsetOptions structure;
  structure.required = required;
  structure.groups = groups;
  if (!structure.is_valid(p, why)) return false;
  if (!(threshold > 0) || !(threshold < 1)) {
    if (why) *why = fmt::format("the threshold must lie in (0, 1), not {}", threshold);
    return false;
  }
  if (max_iterations < 1) {
    if (why) *why = "max_iterations must be at least 1";
    return false;
  }
  return true;
}

SequentialThresholdSummary sequential_threshold(const TriangularSystem& system, const SequentialThresholdOptions& options) {
  SequentialThresholdSummary summary;
  const auto p = static_cast<int>(system.R.cols());
  if (auto why = triangle_problem(system)) {
    summary.message = *why;
    return summary;
  }
  if (!options.is_valid(p, &summary.message)) return summary;
  const Eigen::MatrixXd R = system.R.triangularView<Eigen::Upper>();
  const double norm_b = std::sqrt(system.z.squaredNorm() + system.residual_sum_of_squares);
  std::vector<int> unit_of(static_cast<std::size_t>(p), -1);
  std::vector<std::vector<int>> units = options.groups;
  for (std::size_t u = 0; u < units.size(); ++u)
    for (int c : units[u]) unit_of[static_cast<std::size_t>(c)] = static_cast<int>(u);
  for (int c = 0; c < p; ++c)
    if (unit_of[static_cast<std::size_t>(c)] < 0) {
      unit_of[static_cast<std::size_t>(c)] = static_cast<int>(units.size());
      units.push_back({c});
    }
  std::vector<char> required(units.size(), 0);
  for (int c : options.required) required[static_cast<std::size_t>(unit_of[static_cast<std::size_t>(c)])] = 1;

  std::vector<char> active(units.size(), 1);
  summary.coefficients.assign(static_cast<std::size_t>(p), 0.0);
  summary.scaled.assign(static_cast<std::size_t>(p), 0.0);
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    std::vector<int> support;
    for (int c = 0; c < p; ++c)
      if (active[static_cast<std::size_t>(unit_of[static_cast<std::size_t>(c)])]) support.push_back(c);
    const SubsetSolution fit = solve_subset(system, support);
    summary.path.push_back({support, fit.G});
    summary.support = support;
    summary.G = fit.G;
    std::fill(summary.coefficients.begin(), summary.coefficients.end(), 0.0);
    std::fill(summary.scaled.begin(), summary.scaled.end(), 0.0);
    std::vector<double> largest(units.size(), 0.0);
    for (std::size_t k = 0; k < support.size(); ++k) {
      const auto c = static_cast<std::size_t>(support[k]);
      summary.coefficients[c] = fit.coefficients[k];
      summary.scaled[c] = norm_b > 0 ? std::abs(fit.coefficients[k]) * R.col(support[k]).norm() / norm_b : 0.0;
      auto& l = largest[static_cast<std::size_t>(unit_of[c])];
      l = std::max(l, summary.scaled[c]);
    }
    bool changed = false;
    for (std::size_t u = 0; u < units.size(); ++u)
      if (active[u] && !required[u] && largest[u] < options.threshold) active[u] = 0, changed = true;
    if (!changed) {
      summary.converged = true;
      break;
    }
  }
  summary.termination = SequentialThresholdSummary::Termination::success;
  return summary;
}

std::vector<std::vector<SubsetFit>> threshold_sweep(const TriangularSystem& system, SequentialThresholdOptions options, double smallest,
                                                    double largest, int count) {
  const auto p = static_cast<std::size_t>(system.R.cols());
  std::vector<std::vector<SubsetFit>> best(p + 1);
  for (int i = 0; i < count; ++i) {
    options.threshold = count == 1 ? smallest : smallest * std::pow(largest / smallest, static_cast<double>(i) / (count - 1));
    options.threshold = std::min(options.threshold, 1 - 1e-12);
    const SequentialThresholdSummary s = sequential_threshold(system, options);
    if (s.termination != SequentialThresholdSummary::Termination::success) break;
    // Every support on the path is a candidate for its size, not only the final one.
    for (const auto& step : s.path) {
      auto& kept = best[step.support.size()];
      if (kept.empty() || step.G < kept.front().G) kept = {SubsetFit{step.support, step.G}};
    }
  }
  return best;
}

}  // namespace sidc
