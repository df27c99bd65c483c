// Branch and bound over the triangular factor (see best_subset.hpp).
//
// Relies on: Eigen (HouseholderQR for the root factor and restrict_columns, ColPivHouseholderQR
// for solve_subset). Guarantees: the header's. The search keeps one (m x m) factor per depth in a
// preallocated buffer, so it allocates nothing per node.
#include "runtime/select/best_subset.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

#include <Eigen/Dense>
#include <fmt/format.h>

namespace sidc {

using Index = Eigen::Index;

namespace {

// Power-of-two factor that brings a column's 2-norm into [0.5, 1) (exact: section 3-2, eq. 3-2.4).
double power_of_two_scale(double norm) {
  if (!(norm > 0) || !std::isfinite(norm)) return 1;
  int exponent = 0;
  std::frexp(norm, &exponent);  // norm = f * 2^exponent, f in [0.5, 1)
  return std::ldexp(1.0, exponent);
}

// A unit: columns that enter or leave together (one column unless grouped).
struct Unit {
  std::vector<int> columns;
  int size() const { return static_cast<int>(columns.size()); }
};

class Search {
 public:
  Search(int p, std::vector<Unit> units, int fixed_units, const BestSubsetOptions& options, double tolerance_absolute,
         BestSubsetSummary& summary)
      : p_(p),
        units_(std::move(units)),
        fixed_units_(fixed_units),
        keep_(options.keep_per_size),
        max_size_(options.max_size < 0 ? p : std::min(options.max_size, p)),
        tolerance_(tolerance_absolute),
        summary_(summary),
        threshold_(static_cast<std::size_t>(p + 1), std::numeric_limits<double>::infinity()) {
    const std::size_t depth = units_.size() + 1;
    triangles_.assign(depth, std::vector<double>(static_cast<std::size_t>(p_ * p_), 0.0));
    z_.assign(depth, std::vector<double>(static_cast<std::size_t>(p_), 0.0));
    order_.assign(depth, {});
    summary_.best.assign(static_cast<std::size_t>(p + 1), {});
  }

  // The root: all units, in the order given (fixed ones first), with its factor already in place.
  void run(const Eigen::MatrixXd& T, const Eigen::VectorXd& z, double extra) {
    for (int c = 0; c < p_; ++c)
      for (int r = 0; r <= c; ++r) triangles_[0][static_cast<std::size_t>(r + c * p_)] = T(r, c);
    for (int r = 0; r < p_; ++r) z_[0][static_cast<std::size_t>(r)] = z(r);
    order_[0].resize(units_.size());
    std::iota(order_[0].begin(), order_[0].end(), 0);
    record(0, p_, extra);
    descend(0, p_, fixed_units_, extra);
  }

 private:
  double& at(std::size_t depth, int r, int c) { return triangles_[depth][static_cast<std::size_t>(r + c * p_)]; }

  // Removes column j of the m x m factor at `depth` and restores triangular form by Givens
  // rotations of rows (i, i+1), i = j..m-2; the part of z that leaves the column space is added to G.
  void delete_column(std::size_t depth, int m, int j, double& extra) {
    std::vector<double>& z = z_[depth];
    for (int c = j; c < m - 1; ++c)
      for (int r = 0; r <= c + 1; ++r) at(depth, r, c) = at(depth, r, c + 1);
    for (int i = j; i < m - 1; ++i) {
      const double a = at(depth, i, i), b = at(depth, i + 1, i);
      if (b == 0) continue;
      const double h = std::hypot(a, b), c = a / h, s = b / h;
      at(depth, i, i) = h;
      at(depth, i + 1, i) = 0;
      for (int col = i + 1; col < m - 1; ++col) {
        const double x = at(depth, i, col), y = at(depth, i + 1, col);
        at(depth, i, col) = c * x + s * y;
        at(depth, i + 1, col) = -s * x + c * y;
      }
      const double x = z[static_cast<std::size_t>(i)], y = z[static_cast<std::size_t>(i + 1)];
      z[static_cast<std::size_t>(i)] = c * x + s * y;
      z[static_cast<std::size_t>(i + 1)] = -s * x + c * y;
    }
    const double tail = z[static_cast<std::size_t>(m - 1)];
    extra += tail * tail;
  }

  // Can no subset of the given sizes (bit s of `sizes`) beat the best kept so far, given that none
  // has G below `bound`?
  bool hopeless(std::uint64_t sizes, double bound) const {
    if (max_size_ < 63) sizes &= (std::uint64_t{2} << max_size_) - 1;
    while (sizes) {
      const int s = std::countr_zero(sizes);
      sizes &= sizes - 1;
      if (!(bound > threshold_[static_cast<std::size_t>(s)] + tolerance_)) return false;
    }
    return true;
  }

  void record(std::size_t depth, int m, double G) {
    ++summary_.nodes;
    if (m > max_size_) return;
    auto& kept = summary_.best[static_cast<std::size_t>(m)];
    if (static_cast<int>(kept.size()) == keep_ && !(G < kept.back().G)) return;
    SubsetFit fit;
    fit.G = G;
    for (int u : order_[depth]) fit.columns.insert(fit.columns.end(), units_[static_cast<std::size_t>(u)].columns.begin(),
                                                   units_[static_cast<std::size_t>(u)].columns.end());
    std::sort(fit.columns.begin(), fit.columns.end());
    auto it = std::upper_bound(kept.begin(), kept.end(), G, [](double g, const SubsetFit& f) { return g < f.G; });
    kept.insert(it, std::move(fit));
    if (static_cast<int>(kept.size()) > keep_) kept.pop_back();
    if (static_cast<int>(kept.size()) == keep_) threshold_[static_cast<std::size_t>(m)] = kept.back().G;
  }

  // Node at `depth`: m columns in units order_[depth]; units before `first_free` stay.
  void descend(std::size_t depth, int m, std::size_t first_free, double extra) {
    const std::vector<int>& order = order_[depth];
    const std::size_t U = order.size();
    if (first_free >= U) return;
    // suffix[u]: the subset sums of the sizes of units u..U-1 (bit s set when s is reachable).
    std::vector<std::uint64_t> suffix(U + 1, 1);
    for (std::size_t u = U; u-- > 0;) suffix[u] = suffix[u + 1] | (suffix[u + 1] << units_[static_cast<std::size_t>(order[u])].size());
    int kept_before = 0;  // columns of units 0..u-1
    for (std::size_t u = 0; u < first_free; ++u) kept_before += units_[static_cast<std::size_t>(order[u])].size();
    for (std::size_t u = first_free; u < U; ++u) {
      const int size = units_[static_cast<std::size_t>(order[u])].size();
      // The child's subtree: units 0..u-1 kept, u dropped, any of u+1..U-1.
      const std::uint64_t reach = suffix[u + 1] << kept_before;
      if (!hopeless(reach, extra)) {
        const std::size_t child = depth + 1;
        for (int c = 0; c < m; ++c)
          for (int r = 0; r <= c; ++r) at(child, r, c) = at(depth, r, c);
        std::copy(z_[depth].begin(), z_[depth].begin() + m, z_[child].begin());
        double child_extra = extra;
        for (int k = 0; k < size; ++k) delete_column(child, m - k, kept_before, child_extra);
        order_[child].assign(order.begin(), order.end());
        order_[child].erase(order_[child].begin() + static_cast<std::ptrdiff_t>(u));
        record(child, m - size, child_extra);
        // Below the child: proper subsets only (the child itself is recorded).
        if (u + 1 < U && !hopeless(reach & ~(std::uint64_t{1} << (m - size)), child_extra))
          descend(child, m - size, u, child_extra);
      }
      kept_before += size;
    }
  }

  int p_;
  std::vector<Unit> units_;
  std::size_t fixed_units_;
  int keep_;
  int max_size_;
  double tolerance_;
  BestSubsetSummary& summary_;
  std::vector<double> threshold_;  // per size: G of the keep_-th best so far (infinite until full)
  std::vector<std::vector<double>> triangles_, z_;
  std::vector<std::vector<int>> order_;
};

}  // namespace

bool BestSubsetOptions::is_valid(int p, std::string* why) const {
  auto fail = [&](std::string text) {
    if (why) *why = std::move(text);
    return false;
  };
  if (p > kBestSubsetMaxColumns) return fail(fmt::format("exact search handles at most {} columns, not {}", kBestSubsetMaxColumns, p));
  if (keep_per_size < 1) return fail("keep_per_size must be at least 1");
  if (!(tolerance >= 0) || !std::isfinite(tolerance)) return fail("tolerance must be finite and >= 0");
  std::vector<int> seen(static_cast<std::size_t>(std::max(p, 0)), 0);
  for (int c : required)
    if (c < 0 || c >= p) return fail(fmt::format("required column {} is not among the {} columns", c, p));
  for (const auto& g : groups) {
    if (g.empty()) return fail("a group has no column");
    for (int c : g) {
      if (c < 0 || c >= p) return fail(fmt::format("group column {} is not among the {} columns", c, p));
      if (seen[static_cast<std::size_t>(c)]++) return fail(fmt::format("column {} is in two groups", c));
    }
  }
  return true;
}

BestSubsetSummary best_subsets(const TriangularSystem& system, const BestSubsetOptions& options) {
  BestSubsetSummary summary;
  const auto p = static_cast<int>(system.R.cols());
  if (auto why = triangle_problem(system)) {
    summary.message = *why;
    return summary;
  }
  if (!options.is_valid(p, &summary.message)) return summary;

  // Units: groups, then single columns; required units first (they are never dropped).
  std::vector<int> unit_of(static_cast<std::size_t>(p), -1);
  std::vector<Unit> units;
  for (const auto& g : options.groups) {
    for (int c : g) unit_of[static_cast<std::size_t>(c)] = static_cast<int>(units.size());
    units.push_back({g});
  }
  for (int c = 0; c < p; ++c)
    if (unit_of[static_cast<std::size_t>(c)] < 0) {
      unit_of[static_cast<std::size_t>(c)] = static_cast<int>(units.size());
      units.push_back({{c}});
    }
  std::vector<char> unit_required(units.size(), 0);
  for (int c : options.required) unit_required[static_cast<std::size_t>(unit_of[static_cast<std::size_t>(c)])] = 1;

  // Scaled triangle.
  Eigen::MatrixXd R = system.R.triangularView<Eigen::Upper>();
  for (int c = 0; c < p; ++c) R.col(c) /= power_of_two_scale(R.col(c).norm());
  const double rho2 = system.residual_sum_of_squares;
  summary.G_empty = system.z.squaredNorm() + rho2;
  summary.tolerance_absolute = options.tolerance * summary.G_empty;

  // Order: required units first; the free ones by how much G grows when each alone leaves the
  // full model, largest first. The dropping-column tree gives the first free units the largest
  // subtrees, so putting the important ones there lets the bound cut those subtrees early.
  std::vector<double> importance(units.size(), 0);
  {
    const Eigen::HouseholderQR<Eigen::MatrixXd> full(R);
    for (std::size_t u = 0; u < units.size(); ++u) {
      if (unit_required[u]) continue;
      std::vector<int> rest;
      for (int c = 0; c < p; ++c)
        if (unit_of[static_cast<std::size_t>(c)] != static_cast<int>(u)) rest.push_back(c);
      Eigen::MatrixXd A(p, static_cast<Index>(rest.size()));
      for (std::size_t k = 0; k < rest.size(); ++k) A.col(static_cast<Index>(k)) = R.col(rest[k]);
      const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
      const Eigen::VectorXd x = qr.solve(system.z);
      importance[u] = (system.z - A * x).squaredNorm();
    }
  }
  std::vector<int> order(units.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    if (unit_required[static_cast<std::size_t>(a)] != unit_required[static_cast<std::size_t>(b)])
      return unit_required[static_cast<std::size_t>(a)] > unit_required[static_cast<std::size_t>(b)];
    return importance[static_cast<std::size_t>(a)] > importance[static_cast<std::size_t>(b)];
  });
  std::vector<Unit> ordered;
  std::size_t fixed = 0;
  std::vector<int> permutation;
  for (int u : order) {
    ordered.push_back(units[static_cast<std::size_t>(u)]);
    fixed += unit_required[static_cast<std::size_t>(u)];
    for (int c : units[static_cast<std::size_t>(u)].columns) permutation.push_back(c);
  }
  const std::size_t free_units = ordered.size() - fixed;
  summary.subsets_total = free_units < 64 ? (std::size_t{1} << free_units) : 0;

  // The root factor of the permuted columns: QR of [R P, z] (p x (p+1)).
  Eigen::MatrixXd augmented(p, p + 1);
  for (int k = 0; k < p; ++k) augmented.col(k) = R.col(permutation[static_cast<std::size_t>(k)]);
  augmented.col(p) = system.z;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(augmented);
  const Eigen::MatrixXd T = qr.matrixQR().triangularView<Eigen::Upper>();
  // G of the full set is rho^2: p columns span the p rows of the triangle unless R is exactly
  // singular (then every G here is that of the columns treated as independent; solve_subset and
  // the rank report of the chosen subsets say when that happens).
  Search search(p, std::move(ordered), static_cast<int>(fixed), options, summary.tolerance_absolute, summary);
  search.run(T.leftCols(p), T.col(p), rho2);
  summary.termination = BestSubsetSummary::Termination::success;
  return summary;
}

TriangularSystem restrict_columns(const TriangularSystem& system, const std::vector<int>& columns) {
  TriangularSystem out;
  const Index p = system.R.cols();
  const auto k = static_cast<Index>(columns.size());
  const Eigen::MatrixXd R = system.R.triangularView<Eigen::Upper>();
  Eigen::MatrixXd augmented(p, k + 1);
  for (Index j = 0; j < k; ++j) augmented.col(j) = R.col(columns[static_cast<std::size_t>(j)]);
  augmented.col(k) = system.z;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(augmented);
  const Eigen::MatrixXd QR = qr.matrixQR().triangularView<Eigen::Upper>();
  const Index m = std::min(p, k);
  out.R = Eigen::MatrixXd::Zero(k, k);
  out.R.topRows(m) = QR.topLeftCorner(m, k);
  out.z = Eigen::VectorXd::Zero(k);
  out.z.head(m) = QR.col(k).head(m);
  double tail = 0;
  for (Index r = m; r < p; ++r) tail += QR(r, k) * QR(r, k);
  out.residual_sum_of_squares = system.residual_sum_of_squares + tail;
  out.rows = system.rows;
  out.constant_column = -1;
  for (Index j = 0; j < k; ++j)
    if (columns[static_cast<std::size_t>(j)] == system.constant_column) out.constant_column = static_cast<int>(j);
  out.total_sum_of_squares_centred = system.total_sum_of_squares_centred;
  out.total_sum_of_squares_uncentred = system.total_sum_of_squares_uncentred;
  return out;
}

SubsetSolution solve_subset(const TriangularSystem& system, const std::vector<int>& columns) {
  SubsetSolution solution;
  const Index p = system.R.cols();
  const auto k = static_cast<Index>(columns.size());
  const Eigen::MatrixXd R = system.R.triangularView<Eigen::Upper>();
  if (k == 0) {
    solution.G = system.z.squaredNorm() + system.residual_sum_of_squares;
    return solution;
  }
  Eigen::MatrixXd A(p, k);
  Eigen::VectorXd scale(k);
  for (Index j = 0; j < k; ++j) {
    A.col(j) = R.col(columns[static_cast<std::size_t>(j)]);
    scale(j) = power_of_two_scale(A.col(j).norm());
    A.col(j) /= scale(j);
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  qr.setThreshold(std::numeric_limits<double>::epsilon() * static_cast<double>(std::max(p, k)));
  Eigen::VectorXd u = qr.solve(system.z);
  // One step of refinement against the triangle (cheap: p x k).
  u += qr.solve(system.z - A * u);
  solution.rank = static_cast<int>(qr.rank());
  for (Index j = 0; j < k; ++j) solution.coefficients.push_back(u(j) / scale(j));
  solution.G = (system.z - A * u).squaredNorm() + system.residual_sum_of_squares;
  return solution;
}

double G_at(const TriangularSystem& system, const std::vector<double>& x) {
  const Eigen::Index p = system.R.cols();
  Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(x.data(), p);
  const Eigen::VectorXd r = system.z - system.R.triangularView<Eigen::Upper>() * v;
  return r.squaredNorm() + system.residual_sum_of_squares;
}

}  // namespace sidc
