// The relative-G elbow and the polynomial share of a column (see size_rule.hpp).
//
// Relies on: Eigen (HouseholderQR). Guarantees: the header's.
#include "runtime/select/size_rule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sidc {

ElbowResult relative_g_elbow(const std::vector<double>& G, double share) {
  ElbowResult result;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  result.left.assign(G.size(), nan);
  if (G.size() < 2) return result;
  // G = 0 (an exact fit) is held at the smallest normal number, so that logs stay finite.
  auto clamp = [](double g) { return std::max(g, std::numeric_limits<double>::min()); };
  // Differences of logs, not logs of ratios: G / G_full may overflow when G_full is near 0.
  const double floor = std::log(clamp(G.back()));
  for (std::size_t k = 1; k < G.size(); ++k) {
    const double before = std::log(clamp(G[k - 1])) - floor;
    const double after = std::max(0.0, std::log(clamp(G[k])) - floor);
    if (!(before > 0)) continue;
    result.left[k] = after / before;
    if (result.index < 0 && result.left[k] <= share) result.index = static_cast<int>(k);
  }
  // G never rises with size for the exact search; a heuristic's G may, and then no step need
  // close the distance: the largest size is the elbow (nothing is left after it).
  if (result.index < 0) result.index = static_cast<int>(G.size()) - 1;
  return result;
}

std::vector<double> polynomial_energy_share(const Eigen::Ref<const Eigen::MatrixXd>& values, int degree) {
  const Eigen::Index n = values.rows(), p = values.cols();
  std::vector<double> share(static_cast<std::size_t>(p), std::numeric_limits<double>::quiet_NaN());
  if (n == 0) return share;
  const Eigen::Index terms = std::min<Eigen::Index>(degree + 1, n);
  // Legendre polynomials of x in [-1, 1]: a well-conditioned basis of the same span as 1, t, ..., t^d.
  Eigen::MatrixXd basis(n, terms);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double x = n > 1 ? 2.0 * static_cast<double>(i) / static_cast<double>(n - 1) - 1.0 : 0.0;
    double previous = 1, current = x;
    basis(i, 0) = 1;
    if (terms > 1) basis(i, 1) = x;
    for (Eigen::Index j = 2; j < terms; ++j) {
      const double next = ((2.0 * static_cast<double>(j) - 1) * x * current - (static_cast<double>(j) - 1) * previous) / static_cast<double>(j);
      previous = current, current = next;
      basis(i, j) = next;
    }
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(basis);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(n, terms);
  for (Eigen::Index c = 0; c < p; ++c) {
    const Eigen::VectorXd v = values.col(c);
    const double total = v.squaredNorm();
    if (!(total > 0)) continue;  // the operation does not occur here (or is not finite)
    const double residual = (v - Q * (Q.transpose() * v)).squaredNorm();
    share[static_cast<std::size_t>(c)] = std::clamp(1.0 - residual / total, 0.0, 1.0);
  }
  return share;
}

std::vector<double> operation_line_share(const Eigen::Ref<const Eigen::MatrixXd>& values, int integrations) {
  Eigen::MatrixXd d = values;
  // The I-th forward difference undoes I integrations up to a constant factor h^I and a shift of
  // half a step per integration, neither of which changes the share.
  for (int i = 0; i < integrations && d.rows() > 0; ++i) d = (d.bottomRows(d.rows() - 1) - d.topRows(d.rows() - 1)).eval();
  return polynomial_energy_share(d, 1);
}

}  // namespace sidc
