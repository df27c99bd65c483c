// FROLS on a triangle (see forward_regression.hpp).
//
// Relies on: Eigen (dense vectors of length p). Guarantees: the header's.
#include "runtime/select/forward_regression.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <fmt/format.h>

#include "runtime/select/best_subset.hpp"

namespace sidc {

bool ForwardRegressionOptions::is_valid(int p, std::string* why) const {
  BestSubsetOptions structure;
  structure.required = required;
  structure.groups = groups;
  return structure.is_valid(p, why);
}

namespace {

// The columns of a unit orthogonalized against `basis` and each other; empty vectors for the ones
// that vanish (dependent). Returns the squared norm of the residual's projection onto them.
double projection(const std::vector<Eigen::VectorXd>& basis, const Eigen::MatrixXd& R, const std::vector<int>& columns,
                  const Eigen::VectorXd& residual, std::vector<Eigen::VectorXd>* orthonormal) {
  std::vector<Eigen::VectorXd> own;
  double explained = 0;
  for (int c : columns) {
    Eigen::VectorXd q = R.col(c);
    const double original = q.norm();
    for (int pass = 0; pass < 2; ++pass) {
      for (const auto& b : basis) q -= b.dot(q) * b;
      for (const auto& b : own) q -= b.dot(q) * b;
    }
    const double norm = q.norm();
    if (!(original > 0) || norm <= 1e-12 * original) continue;
    q /= norm;
    const double along = q.dot(residual);
    explained += along * along;
    own.push_back(std::move(q));
  }
  if (orthonormal) *orthonormal = std::move(own);
  return explained;
}

}  // namespace

ForwardRegressionSummary forward_regression(const TriangularSystem& system, const ForwardRegressionOptions& options) {
  ForwardRegressionSummary summary;
  const auto p = static_cast<int>(system.R.cols());
  if (auto why = triangle_problem(system)) {
    summary.message = *why;
    return summary;
  }
  if (!options.is_valid(p, &summary.message)) return summary;
  const Eigen::MatrixXd R = system.R.triangularView<Eigen::Upper>();
  summary.G_empty = system.z.squaredNorm() + system.residual_sum_of_squares;
  const double G0 = summary.G_empty > 0 ? summary.G_empty : 1.0;

  std::vector<int> unit_of(static_cast<std::size_t>(p), -1);
  std::vector<std::vector<int>> units = options.groups;
  for (std::size_t u = 0; u < units.size(); ++u)
    for (int c : units[u]) unit_of[static_cast<std::size_t>(c)] = static_cast<int>(u);
  for (int c = 0; c < p; ++c)
    if (unit_of[static_cast<std::size_t>(c)] < 0) {
      unit_of[static_cast<std::size_t>(c)] = static_cast<int>(units.size());
      units.push_back({c});
    }
  std::vector<char> required(units.size(), 0), chosen(units.size(), 0);
  for (int c : options.required) required[static_cast<std::size_t>(unit_of[static_cast<std::size_t>(c)])] = 1;
  // Required units in order of their first column.
  std::vector<std::size_t> forced;
  for (int c = 0; c < p; ++c) {
    const auto u = static_cast<std::size_t>(unit_of[static_cast<std::size_t>(c)]);
    if (required[u] && std::find(forced.begin(), forced.end(), u) == forced.end()) forced.push_back(u);
  }

  std::vector<Eigen::VectorXd> basis;
  Eigen::VectorXd residual = system.z;
  int terms = 0;
  double cumulative = 0;
  const int limit = options.max_terms < 0 ? p : options.max_terms;
  std::size_t next_forced = 0;
  while (true) {
    std::size_t pick = units.size();
    double best = -1;
    if (next_forced < forced.size()) {
      pick = forced[next_forced++];
      best = projection(basis, R, units[pick], residual, nullptr);
    } else {
      for (std::size_t u = 0; u < units.size(); ++u) {
        if (chosen[u] || terms + static_cast<int>(units[u].size()) > limit) continue;
        const double e = projection(basis, R, units[u], residual, nullptr);
        if (e > best) best = e, pick = u;
      }
    }
    if (pick == units.size()) break;
    std::vector<Eigen::VectorXd> added;
    projection(basis, R, units[pick], residual, &added);
    for (auto& q : added) {
      residual -= q.dot(residual) * q;
      basis.push_back(std::move(q));
    }
    chosen[pick] = 1;
    terms += static_cast<int>(units[pick].size());
    ForwardStep step;
    step.entered = units[pick];
    std::sort(step.entered.begin(), step.entered.end());
    step.required = required[pick] != 0;
    step.err = best / G0;
    step.G = residual.squaredNorm() + system.residual_sum_of_squares;
    cumulative = 1 - step.G / G0;
    step.cumulative_err = cumulative;
    summary.steps.push_back(std::move(step));
  }
  summary.termination = ForwardRegressionSummary::Termination::success;
  return summary;
}

}  // namespace sidc
