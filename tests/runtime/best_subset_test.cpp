// Unit tests of runtime/select/best_subset.*: the branch and bound against brute force over every subset.
//
// The reference G of each subset is computed independently of the search: from the original rows
// (not the triangle) by column-pivoted QR, in long double for the ill-conditioned designs. Designs:
// Gaussian random (p = 13, 11, 12), and
// ill-conditioned ones (monomials t^0..t^11 on [0, 1], condition about 1e8 after scaling; and
// random columns with near copies and column scales 1e-6 to 1e8). Each test can fail: a wrong bound, a wrong Givens update or a
// wrong size bookkeeping changes some size's best G or subset.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "runtime/select/best_subset.hpp"
#include "runtime/solve/triangular_accumulator.hpp"

namespace sidc {
namespace {


TriangularSystem triangle_of(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) {
  TriangularAccumulator accumulator(static_cast<int>(A.cols()));
  EXPECT_TRUE(accumulator.add_rows(A, b, nullptr));
  return accumulator.system();
}

// Long double for the ill-conditioned designs; double (several times faster in a Debug build) where
// the design is well conditioned and double QR is accurate to far below the tolerance.
template <typename Scalar>
double reference_G_in(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, const std::vector<int>& columns) {
  using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
  using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  const Vector lb = b.cast<Scalar>();
  if (columns.empty()) return static_cast<double>(lb.squaredNorm());
  Matrix S(A.rows(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t k = 0; k < columns.size(); ++k) S.col(static_cast<Eigen::Index>(k)) = A.col(columns[k]).cast<Scalar>();
  const Eigen::ColPivHouseholderQR<Matrix> qr(S);
  const Vector x = qr.solve(lb);
  return static_cast<double>((lb - S * x).squaredNorm());
}

bool use_long_double = true;

double reference_G(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, const std::vector<int>& columns) {
  return use_long_double ? reference_G_in<long double>(A, b, columns) : reference_G_in<double>(A, b, columns);
}

struct Reference {
  std::map<int, std::vector<std::pair<double, std::vector<int>>>> by_size;  // sorted by G
};

// Every subset that contains the required columns and keeps each group whole.
Reference brute_force(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, const std::vector<int>& required,
                      const std::vector<std::vector<int>>& groups) {
  const int p = static_cast<int>(A.cols());
  Reference ref;
  for (std::uint32_t mask = 0; mask < (1u << p); ++mask) {
    bool ok = true;
    for (int c : required) ok = ok && (mask >> c & 1u);
    for (const auto& g : groups)
      for (int c : g) {
        ok = ok && ((mask >> c & 1u) == (mask >> g.front() & 1u));
      }
    if (!ok) continue;
    std::vector<int> columns;
    for (int c = 0; c < p; ++c)
      if (mask >> c & 1u) columns.push_back(c);
    ref.by_size[static_cast<int>(columns.size())].emplace_back(reference_G(A, b, columns), columns);
  }
  for (auto& [size, list] : ref.by_size) std::sort(list.begin(), list.end());
  return ref;
}

void expect_matches_brute_force(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, BestSubsetOptions options, bool long_double = true) {
  use_long_double = long_double;
  const TriangularSystem system = triangle_of(A, b);
  const BestSubsetSummary found = best_subsets(system, options);
  ASSERT_EQ(found.termination, BestSubsetSummary::Termination::success) << found.message;
  const Reference ref = brute_force(A, b, options.required, options.groups);
  // The triangle's own rounding (double QR of the rows) adds to the search tolerance.
  const double slack = 2 * found.tolerance_absolute + 1e-13 * found.G_empty;
  const int p = static_cast<int>(A.cols());
  for (int s = 0; s <= p; ++s) {
    const auto& got = found.best[static_cast<std::size_t>(s)];
    const auto it = ref.by_size.find(s);
    const bool allowed = it != ref.by_size.end() && (options.max_size < 0 || s <= options.max_size);
    if (!allowed) {
      EXPECT_TRUE(got.empty()) << "size " << s;
      continue;
    }
    const auto& want = it->second;
    ASSERT_EQ(got.size(), std::min<std::size_t>(want.size(), static_cast<std::size_t>(options.keep_per_size))) << "size " << s;
    for (std::size_t r = 0; r < got.size(); ++r) {
      EXPECT_NEAR(got[r].G, want[r].first, slack) << "size " << s << " rank " << r;
      const bool separated = (r == 0 || want[r].first - want[r - 1].first > 2 * slack) &&
                             (r + 1 >= want.size() || want[r + 1].first - want[r].first > 2 * slack);
      if (separated) {
        EXPECT_EQ(got[r].columns, want[r].second) << "size " << s << " rank " << r;
      }
      EXPECT_NEAR(reference_G(A, b, got[r].columns), got[r].G, slack) << "the reported G belongs to the reported subset";
    }
  }
  EXPECT_LE(found.nodes, found.subsets_total);
}

Eigen::MatrixXd gaussian(int n, int p, unsigned seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(n, p);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < p; ++j) A(i, j) = normal(generator);
  return A;
}

Eigen::VectorXd sparse_response(const Eigen::MatrixXd& A, const std::vector<std::pair<int, double>>& truth, double noise, unsigned seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> normal;
  Eigen::VectorXd b = Eigen::VectorXd::Zero(A.rows());
  for (auto [c, v] : truth) b += v * A.col(c);
  for (Eigen::Index i = 0; i < b.size(); ++i) b(i) += noise * normal(generator);
  return b;
}

TEST(BestSubset, MatchesBruteForceOnRandomDesign) {
  const Eigen::MatrixXd A = gaussian(24, 13, 3);
  const Eigen::VectorXd b = sparse_response(A, {{1, 2.0}, {4, -1.0}, {9, 0.5}, {12, 0.2}}, 0.3, 4);
  expect_matches_brute_force(A, b, {}, false);
}

TEST(BestSubset, MatchesBruteForceKeepingThreePerSize) {
  const Eigen::MatrixXd A = gaussian(24, 11, 5);
  const Eigen::VectorXd b = sparse_response(A, {{0, 1.0}, {5, 1.0}}, 1.0, 6);
  BestSubsetOptions options;
  options.keep_per_size = 3;
  expect_matches_brute_force(A, b, options, false);
}

TEST(BestSubset, MatchesBruteForceOnIllConditionedMonomials) {
  const int n = 30, p = 12;
  Eigen::MatrixXd A(n, p);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < p; ++j) A(i, j) = std::pow(static_cast<double>(i) / (n - 1), j);
  const Eigen::VectorXd b = sparse_response(A, {{0, 1.0}, {3, -2.0}, {7, 0.5}}, 1e-3, 7);
  expect_matches_brute_force(A, b, {});
}

TEST(BestSubset, MatchesBruteForceWithNearCopiesAndWildScales) {
  Eigen::MatrixXd A = gaussian(30, 11, 8);
  const Eigen::MatrixXd E = gaussian(30, 3, 9);
  A.col(5) = A.col(2) + 1e-6 * E.col(0);  // nearly dependent
  A.col(9) = A.col(1) - A.col(3) + 1e-7 * E.col(1);
  A.col(7) *= 1e8;  // scales far apart
  A.col(10) *= 1e-6;
  const Eigen::VectorXd b = sparse_response(A, {{2, 1.0}, {3, 1.0}, {7, 1e-8}}, 0.05, 10);
  expect_matches_brute_force(A, b, {});
}

TEST(BestSubset, RequiredColumnsAndGroupsMatchBruteForce) {
  const Eigen::MatrixXd A = gaussian(30, 13, 11);
  const Eigen::VectorXd b = sparse_response(A, {{0, 1.0}, {4, 1.0}, {5, -1.0}, {11, 0.3}}, 0.2, 12);
  BestSubsetOptions options;
  options.required = {0};
  options.groups = {{4, 5, 6}, {8, 9}, {1, 12}};
  options.keep_per_size = 2;
  expect_matches_brute_force(A, b, options);
}

TEST(BestSubset, MaxSizeLimitsTheReportAndStaysExact) {
  const Eigen::MatrixXd A = gaussian(24, 12, 13);
  const Eigen::VectorXd b = sparse_response(A, {{2, 1.0}, {6, 1.0}, {7, -1.0}}, 0.2, 14);
  BestSubsetOptions options;
  options.max_size = 4;
  expect_matches_brute_force(A, b, options, false);
}

TEST(BestSubset, FindsTheTrueSupportAndPrunes) {
  const Eigen::MatrixXd A = gaussian(400, 20, 15);
  const Eigen::VectorXd b = sparse_response(A, {{3, 1.0}, {8, -2.0}, {15, 0.7}}, 0.01, 16);
  const BestSubsetSummary found = best_subsets(triangle_of(A, b), {});
  ASSERT_EQ(found.termination, BestSubsetSummary::Termination::success);
  EXPECT_EQ(found.best[3].front().columns, (std::vector<int>{3, 8, 15}));
  EXPECT_LT(found.nodes, found.subsets_total / 10) << "the bound should cut most of the 2^20 subsets";
}

TEST(BestSubset, RejectsBadInput) {
  TriangularSystem system;
  system.R = Eigen::MatrixXd::Identity(3, 3);
  system.z = Eigen::VectorXd::Ones(3);
  BestSubsetOptions options;
  options.required = {5};
  EXPECT_EQ(best_subsets(system, options).termination, BestSubsetSummary::Termination::invalid_input);
  options = {};
  options.groups = {{0, 1}, {1, 2}};
  EXPECT_EQ(best_subsets(system, options).termination, BestSubsetSummary::Termination::invalid_input);
  system.z(1) = std::nan("");
  EXPECT_EQ(best_subsets(system, {}).termination, BestSubsetSummary::Termination::invalid_input);
}

TEST(BestSubset, SolveSubsetAndGAtAgreeWithTheRows) {
  const Eigen::MatrixXd A = gaussian(60, 6, 17);
  const Eigen::VectorXd b = sparse_response(A, {{0, 1.0}, {2, 3.0}}, 0.5, 18);
  const TriangularSystem system = triangle_of(A, b);
  const std::vector<int> columns{0, 2, 5};
  const SubsetSolution s = solve_subset(system, columns);
  EXPECT_NEAR(s.G, reference_G(A, b, columns), 1e-10 * b.squaredNorm());
  std::vector<double> x(6, 0.0);
  for (std::size_t k = 0; k < columns.size(); ++k) x[static_cast<std::size_t>(columns[k])] = s.coefficients[k];
  EXPECT_NEAR(G_at(system, x), s.G, 1e-10 * b.squaredNorm());
  const TriangularSystem restricted = restrict_columns(system, columns);
  EXPECT_NEAR(solve_subset(restricted, {0, 1, 2}).G, s.G, 1e-10 * b.squaredNorm());
}

}  // namespace
}  // namespace sidc
