// Unit tests of runtime/solve/least_squares.* and runtime/solve/triangular_accumulator.*.
//
// Problems are constructed so that the answer is known independently of the solver: exact
// solutions (integer data), residual vectors built orthogonal to the columns (so the parameters
// are exact and G is known), the normal equations in long double for the covariance, and a
// textbook Student t quantile. The NIST StRD sets are in tests/nist/.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "runtime/solve/least_squares.hpp"
#include "runtime/solve/triangular_accumulator.hpp"

namespace sidc {
namespace {

using Termination = LeastSquaresSummary::Termination;

std::vector<std::string> names_of(int p) {
  std::vector<std::string> names;
  // (Not "a" + std::to_string(...): GCC 12 warns -Wrestrict on it, a false positive.)
  for (int j = 0; j < p; ++j) names.push_back(std::string("a").append(std::to_string(j + 1)));
  return names;
}

Eigen::MatrixXd random_matrix(int n, int p, unsigned seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(n, p);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < p; ++j) A(i, j) = normal(generator);
  }
  return A;
}

// A vector orthogonal to the columns of A, of 2-norm `size`: then x_true is the exact least-squares
// solution of A x = A x_true + e, and G = size^2.
Eigen::VectorXd orthogonal_residual(const Eigen::MatrixXd& A, double size, unsigned seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> normal;
  Eigen::VectorXd e(A.rows());
  for (Eigen::Index i = 0; i < e.size(); ++i) e(i) = normal(generator);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(A.rows(), A.cols());
  e -= Q * (Q.transpose() * e);
  e -= Q * (Q.transpose() * e);  // twice is enough (Kahan)
  return e * (size / e.norm());
}

double relative_error(double estimate, double truth) { return std::abs(estimate - truth) / std::abs(truth); }

TEST(LeastSquares, RecoversExactSolutionOfIntegerSystem) {
  std::mt19937 generator(7);
  std::uniform_int_distribution<int> digit(-9, 9);
  Eigen::MatrixXd A(40, 4);
  for (Eigen::Index i = 0; i < A.rows(); ++i) {
    for (Eigen::Index j = 0; j < A.cols(); ++j) A(i, j) = digit(generator);
  }
  const Eigen::Vector4d truth(3, -2, 0.5, 7);
  const Eigen::VectorXd b = A * truth;  // small integers and halves: exact
  const LeastSquaresSummary summary = solve_least_squares(A, b, names_of(4), nullptr, {});
  ASSERT_EQ(summary.termination, Termination::success) << summary.message;
  EXPECT_TRUE(summary.is_solution_usable());
  EXPECT_EQ(summary.rank, 4u);
  EXPECT_EQ(summary.n, 40u);
  for (int j = 0; j < 4; ++j) EXPECT_NEAR(summary.parameters[static_cast<std::size_t>(j)].value, truth(j), 1e-14);
  EXPECT_LT(summary.G, 1e-24);
  ASSERT_EQ(summary.residuals.size(), 40u);
  for (double residual : summary.residuals) EXPECT_LT(std::abs(residual), 1e-12);
  EXPECT_EQ(summary.parameters[2].name, "a3");
}

TEST(LeastSquares, ResidualOrthogonalToColumnsGivesKnownParametersAndG) {
  const Eigen::MatrixXd A = random_matrix(60, 3, 1);
  const Eigen::Vector3d truth(1.5, -0.25, 4);
  const Eigen::VectorXd e = orthogonal_residual(A, 3.0, 2);
  const Eigen::VectorXd b = A * truth + e;
  const LeastSquaresSummary summary = solve_least_squares(A, b, names_of(3), nullptr, {});
  ASSERT_EQ(summary.termination, Termination::success);
  for (int j = 0; j < 3; ++j) EXPECT_LT(relative_error(summary.parameters[static_cast<std::size_t>(j)].value, truth(j)), 1e-13);
  EXPECT_NEAR(summary.G, 9.0, 1e-12);  // eq. 2-1.7
  EXPECT_NEAR(summary.standard_error, std::sqrt(9.0 / 60), 1e-14);  // Table 4-1.2: sqrt(G/n)
  EXPECT_NEAR(summary.residual_sd, std::sqrt(9.0 / 57), 1e-14);
  for (Eigen::Index i = 0; i < e.size(); ++i) EXPECT_NEAR(summary.residuals[static_cast<std::size_t>(i)], e(i), 1e-13);
  EXPECT_NEAR(summary.aic, 60 * std::log(9.0 / 60) + 2 * 3, 1e-11);
  EXPECT_NEAR(summary.bic, 60 * std::log(9.0 / 60) + 3 * std::log(60.0), 1e-11);
}

TEST(LeastSquares, StandardErrorsEqualNormalEquationCovariance) {
  const Eigen::MatrixXd A = random_matrix(50, 4, 3);
  Eigen::VectorXd b = A * Eigen::Vector4d(1, 2, 3, 4);
  std::mt19937 generator(4);
  std::normal_distribution<double> normal(0, 0.1);
  for (Eigen::Index i = 0; i < b.size(); ++i) b(i) += normal(generator);
  const LeastSquaresSummary summary = solve_least_squares(A, b, names_of(4), nullptr, {});
  ASSERT_EQ(summary.termination, Termination::success);
  // Independent route: (A^T A)^-1 in long double; the matrix is well conditioned.
  using MatrixL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
  const MatrixL AL = A.cast<long double>();
  const MatrixL inverse = (AL.transpose() * AL).inverse();
  const long double variance = static_cast<long double>(summary.G) / (50 - 4);
  for (int j = 0; j < 4; ++j) {
    const double expected = static_cast<double>(std::sqrt(variance * inverse(j, j)));
    EXPECT_LT(relative_error(summary.parameters[static_cast<std::size_t>(j)].standard_error, expected), 1e-12);
    EXPECT_LT(relative_error(summary.covariance(j, (j + 1) % 4), static_cast<double>(variance * inverse(j, (j + 1) % 4))),
              1e-11);
  }
}

TEST(LeastSquares, ConfidenceIntervalUsesStudentTQuantile) {
  const Eigen::MatrixXd A = random_matrix(12, 2, 5);
  const Eigen::VectorXd b = A * Eigen::Vector2d(1, -1) + orthogonal_residual(A, 1.0, 6);
  const LeastSquaresSummary summary = solve_least_squares(A, b, names_of(2), nullptr, {});
  ASSERT_EQ(summary.termination, Termination::success);
  // t_{0.975} with 10 degrees of freedom, from the tables: 2.228138851986...
  for (const ParameterEstimate& estimate : summary.parameters) {
    EXPECT_NEAR((estimate.ci_high - estimate.value) / estimate.standard_error, 2.2281388519862744, 1e-9);
    EXPECT_NEAR((estimate.value - estimate.ci_low) / estimate.standard_error, 2.2281388519862744, 1e-9);
  }
}

TEST(LeastSquares, WeightsMultiplyRows) {
  const Eigen::MatrixXd A = random_matrix(30, 3, 8);
  Eigen::VectorXd b = A * Eigen::Vector3d(2, 0.5, -1);
  std::mt19937 generator(9);
  std::uniform_real_distribution<double> uniform(0.1, 1.0);
  Eigen::VectorXd w(30);
  for (Eigen::Index i = 0; i < 30; ++i) {
    w(i) = uniform(generator);
    b(i) += uniform(generator) - 0.5;
  }
  const LeastSquaresSummary weighted = solve_least_squares(A, b, names_of(3), &w, {});
  const Eigen::MatrixXd scaled_A = w.asDiagonal() * A;
  const Eigen::VectorXd scaled_b = w.asDiagonal() * b;
  const LeastSquaresSummary scaled = solve_least_squares(scaled_A, scaled_b, names_of(3), nullptr, {});
  ASSERT_EQ(weighted.termination, Termination::success);
  for (std::size_t j = 0; j < 3; ++j) {
    EXPECT_LT(relative_error(weighted.parameters[j].value, scaled.parameters[j].value), 1e-13);
    EXPECT_LT(relative_error(weighted.parameters[j].standard_error, scaled.parameters[j].standard_error), 1e-12);
  }
  EXPECT_LT(relative_error(weighted.G, scaled.G), 1e-13);
  // Residuals are unweighted (b - A x); G weighs them (eq. 2-1.6).
  double G = 0;
  for (Eigen::Index i = 0; i < 30; ++i) {
    const double residual = b(i) - A.row(i).dot(Eigen::Vector3d(weighted.parameters[0].value, weighted.parameters[1].value,
                                                                weighted.parameters[2].value));
    EXPECT_NEAR(weighted.residuals[static_cast<std::size_t>(i)], residual, 1e-13);
    G += w(i) * w(i) * residual * residual;
  }
  EXPECT_LT(relative_error(weighted.G, G), 1e-12);
}

TEST(LeastSquares, ZeroWeightRemovesRow) {
  const Eigen::MatrixXd A = random_matrix(20, 2, 10);
  Eigen::VectorXd b = A * Eigen::Vector2d(1, 3);
  b(4) += 100;  // an outlier, weighted out
  b(7) += 0.3;
  Eigen::VectorXd w = Eigen::VectorXd::Ones(20);
  w(4) = 0;
  const LeastSquaresSummary weighted = solve_least_squares(A, b, names_of(2), &w, {});
  Eigen::MatrixXd A_kept(19, 2);
  Eigen::VectorXd b_kept(19);
  for (Eigen::Index i = 0, k = 0; i < 20; ++i) {
    if (i == 4) continue;
    A_kept.row(k) = A.row(i);
    b_kept(k++) = b(i);
  }
  const LeastSquaresSummary kept = solve_least_squares(A_kept, b_kept, names_of(2), nullptr, {});
  EXPECT_EQ(weighted.n, 19u);
  EXPECT_EQ(weighted.residuals.size(), 20u);
  for (std::size_t j = 0; j < 2; ++j) {
    EXPECT_LT(relative_error(weighted.parameters[j].value, kept.parameters[j].value), 1e-13);
    EXPECT_LT(relative_error(weighted.parameters[j].standard_error, kept.parameters[j].standard_error), 1e-12);
  }
  EXPECT_LT(relative_error(weighted.residual_sd, kept.residual_sd), 1e-12);
}

TEST(LeastSquares, RankDeficiencyNamesTheDependentColumns) {
  const Eigen::MatrixXd base = random_matrix(25, 3, 11);
  Eigen::MatrixXd A(25, 4);
  A.col(0) = base.col(0);
  A.col(1) = base.col(1);
  A.col(2) = base.col(0) + 2 * base.col(1);  // dependent on the first two
  A.col(3) = base.col(2);
  const Eigen::VectorXd b = base * Eigen::Vector3d(1, 2, 3) + orthogonal_residual(base, 0.5, 12);
  const std::vector<std::string> names = {"y'", "y", "y'+2y", "x"};
  const LeastSquaresSummary summary = solve_least_squares(A, b, names, nullptr, {});
  ASSERT_EQ(summary.termination, Termination::rank_deficient);
  EXPECT_FALSE(summary.is_solution_usable());
  EXPECT_EQ(summary.rank, 3u);
  ASSERT_EQ(summary.dependent_groups.size(), 1u);
  std::vector<std::string> group = summary.dependent_groups[0];
  std::sort(group.begin(), group.end());
  EXPECT_EQ(group, (std::vector<std::string>{"y", "y'", "y'+2y"}));
  EXPECT_NE(summary.message.find("depends on"), std::string::npos) << summary.message;
  // The dropped column has no standard error; the fit with the others is still the best one.
  int not_estimable = 0;
  for (const ParameterEstimate& estimate : summary.parameters) not_estimable += std::isnan(estimate.standard_error);
  EXPECT_EQ(not_estimable, 1);
  EXPECT_NEAR(summary.G, 0.25, 1e-12);
  EXPECT_FALSE(std::isfinite(summary.condition_after) && summary.condition_after < 1e12);
}

TEST(LeastSquares, DuplicateAndZeroColumnsAreNamed) {
  const Eigen::MatrixXd base = random_matrix(15, 2, 13);
  Eigen::MatrixXd A(15, 4);
  A.col(0) = base.col(0);
  A.col(1) = base.col(1);
  A.col(2) = base.col(1);            // a copy
  A.col(3) = Eigen::VectorXd::Zero(15);  // identically zero
  const Eigen::VectorXd b = base * Eigen::Vector2d(1, 1);
  const LeastSquaresSummary summary = solve_least_squares(A, b, {"u", "v", "v copy", "zero"}, nullptr, {});
  ASSERT_EQ(summary.termination, Termination::rank_deficient);
  EXPECT_EQ(summary.rank, 2u);
  ASSERT_EQ(summary.dependent_groups.size(), 2u);
  bool zero_alone = false, copy_pair = false;
  for (std::vector<std::string> group : summary.dependent_groups) {
    std::sort(group.begin(), group.end());
    zero_alone |= group == std::vector<std::string>{"zero"};
    copy_pair |= group == std::vector<std::string>{"v", "v copy"};
  }
  EXPECT_TRUE(zero_alone);
  EXPECT_TRUE(copy_pair);
}

TEST(LeastSquares, AllZeroDesignIsRankZeroNotACrash) {
  const Eigen::MatrixXd A = Eigen::MatrixXd::Zero(8, 2);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(8, 1, 8);
  const LeastSquaresSummary summary = solve_least_squares(A, b, {"y'", "y"}, nullptr, {});
  EXPECT_EQ(summary.termination, Termination::rank_deficient);
  EXPECT_EQ(summary.rank, 0u);
  EXPECT_EQ(summary.dependent_groups.size(), 2u);
  EXPECT_DOUBLE_EQ(summary.G, b.squaredNorm());  // nothing is explained
  for (const ParameterEstimate& estimate : summary.parameters) {
    EXPECT_EQ(estimate.value, 0.0);
    EXPECT_TRUE(std::isnan(estimate.standard_error));
  }
  EXPECT_FALSE(summary.brief_report().empty());
}

// Thesis eq. 3-2.1: a1 y' + a2 y' y + a3 y^2 = x with y' much larger than y, so the columns differ
// by orders of magnitude and the unscaled normal equations (3-2.3) are poorly conditioned.
TEST(LeastSquares, ScalingReducesTheConditionOfTheThesisExample) {
  const int n = 200;
  Eigen::MatrixXd A(n, 3);
  Eigen::VectorXd x(n);
  const Eigen::Vector3d truth(0.8, -3.0, 2.5e4);
  for (int i = 0; i < n; ++i) {
    const double t = 0.005 * i;
    const double y = 1e-3 * (std::sin(1000 * t) + 0.3 * std::cos(700 * t));
    const double y_dot = std::cos(1000 * t) - 0.21 * std::sin(700 * t);  // d/dt of y
    A(i, 0) = y_dot;
    A(i, 1) = y_dot * y;
    A(i, 2) = y * y;
    x(i) = A.row(i).dot(truth);
  }
  const std::vector<std::string> names = {"y'", "y'*y", "y^2"};
  LeastSquaresOptions scaled_options;
  const LeastSquaresSummary scaled = solve_least_squares(A, x, names, nullptr, scaled_options);
  LeastSquaresOptions unscaled_options;
  unscaled_options.scale_columns = false;
  const LeastSquaresSummary unscaled = solve_least_squares(A, x, names, nullptr, unscaled_options);
  ASSERT_EQ(scaled.termination, Termination::success);
  EXPECT_TRUE(scaled.columns_scaled);
  EXPECT_GT(scaled.condition_before, 1e5);
  EXPECT_LT(scaled.condition_after, 20);
  EXPECT_GT(scaled.condition_before / scaled.condition_after, 1e4);
  EXPECT_NEAR(unscaled.condition_after / unscaled.condition_before, 1.0, 1e-6);  // nothing scaled
  EXPECT_NEAR(scaled.condition_before / unscaled.condition_before, 1.0, 1e-6);   // same design
  EXPECT_NEAR(scaled.digits_lost_estimate, std::log10(scaled.condition_after), 1e-12);
  for (int j = 0; j < 3; ++j) EXPECT_LT(relative_error(scaled.parameters[static_cast<std::size_t>(j)].value, truth(j)), 1e-12);
}

TEST(LeastSquares, InvalidInputIsAStatusNotAnAbort) {
  const Eigen::MatrixXd A = random_matrix(10, 2, 14);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(10);
  const auto expect_status = [](const LeastSquaresSummary& summary, Termination expected, const char* what) {
    EXPECT_EQ(summary.termination, expected) << what;
    EXPECT_FALSE(summary.message.empty()) << what;
    EXPECT_FALSE(summary.is_solution_usable()) << what;
    for (const ParameterEstimate& estimate : summary.parameters) EXPECT_TRUE(std::isnan(estimate.value)) << what;
    EXPECT_FALSE(summary.full_report().empty());
  };
  Eigen::MatrixXd with_nan = A;
  with_nan(3, 1) = std::numeric_limits<double>::quiet_NaN();
  expect_status(solve_least_squares(with_nan, b, names_of(2), nullptr, {}), Termination::invalid_input, "NaN in A");
  Eigen::VectorXd b_inf = b;
  b_inf(2) = std::numeric_limits<double>::infinity();
  expect_status(solve_least_squares(A, b_inf, names_of(2), nullptr, {}), Termination::invalid_input, "inf in b");
  expect_status(solve_least_squares(A, b, names_of(3), nullptr, {}), Termination::invalid_input, "names");
  expect_status(solve_least_squares(A, Eigen::VectorXd::Ones(9), names_of(2), nullptr, {}), Termination::invalid_input,
                "b size");
  Eigen::VectorXd w = Eigen::VectorXd::Ones(10);
  w(5) = -1;
  expect_status(solve_least_squares(A, b, names_of(2), &w, {}), Termination::invalid_input, "negative weight");
  const Eigen::VectorXd short_w = Eigen::VectorXd::Ones(4);
  expect_status(solve_least_squares(A, b, names_of(2), &short_w, {}), Termination::invalid_input, "weights size");
  expect_status(solve_least_squares(Eigen::MatrixXd(10, 0), b, {}, nullptr, {}), Termination::invalid_input, "p = 0");
  expect_status(solve_least_squares(A.topRows(1), b.head(1), names_of(2), nullptr, {}), Termination::too_few_rows,
                "n < p");
  Eigen::VectorXd mostly_zero = Eigen::VectorXd::Zero(10);
  mostly_zero(0) = 1;
  expect_status(solve_least_squares(A, b, names_of(2), &mostly_zero, {}), Termination::too_few_rows,
                "one weighted row");
  LeastSquaresOptions options;
  options.refinement_steps = -1;
  std::string why;
  EXPECT_FALSE(options.is_valid(&why));
  EXPECT_FALSE(why.empty());
  expect_status(solve_least_squares(A, b, names_of(2), nullptr, options), Termination::invalid_input, "options");
  options = {};
  options.rank_tolerance = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(options.is_valid(nullptr));
  options = {};
  options.confidence_level = 1.5;
  EXPECT_FALSE(options.is_valid(nullptr));
  EXPECT_TRUE(LeastSquaresOptions{}.is_valid(nullptr));
}

TEST(LeastSquares, ExactlyDeterminedSystemHasNoStandardErrors) {
  const Eigen::MatrixXd A = random_matrix(3, 3, 15);
  const Eigen::VectorXd b = A * Eigen::Vector3d(1, 2, 3);
  const LeastSquaresSummary summary = solve_least_squares(A, b, names_of(3), nullptr, {});
  ASSERT_EQ(summary.termination, Termination::success);  // the thesis' m equations in m unknowns
  for (int j = 0; j < 3; ++j) EXPECT_NEAR(summary.parameters[static_cast<std::size_t>(j)].value, j + 1.0, 1e-13);
  EXPECT_TRUE(std::isnan(summary.residual_sd));
  EXPECT_TRUE(std::isnan(summary.parameters[0].standard_error));
}

// Issue 19: a record in other units is the same fit. Columns and known side multiplied by s leave
// the parameters, their relative standard errors and R^2 as they were; sqrt(G/n) scales by s and
// AIC, BIC shift by 2 n log s. Before, s = 1e200 gave infinite standard errors (G overflowed a
// double), s = 1e-300 zero ones (G underflowed: a false exact fit) and subnormal data NaN.
TEST(LeastSquares, StatisticsAreScaleInvariant) {
  Eigen::MatrixXd A = random_matrix(80, 3, 21);
  A.col(0).setOnes();  // an intercept, so R^2 is the centred one
  std::mt19937 generator(22);
  std::normal_distribution<double> noise(0, 0.05);
  Eigen::VectorXd b = A * Eigen::Vector3d(0.5, -2, 3);
  for (Eigen::Index i = 0; i < b.size(); ++i) b(i) += noise(generator);
  for (Precision precision : {Precision::extended, Precision::double_precision}) {
    LeastSquaresOptions options;
    options.precision = precision;
    const LeastSquaresSummary reference = solve_least_squares(A, b, names_of(3), nullptr, options);
    ASSERT_EQ(reference.termination, Termination::success);
    EXPECT_TRUE(unrepresentable_statistics(reference).empty());
    // 1e-310 is subnormal: the data themselves keep only about 44 bits, hence the wider tolerance.
    for (const auto& [scale, tolerance] : {std::pair{1e200, 1e-12}, std::pair{1e-300, 1e-12}, std::pair{1e-310, 1e-9}}) {
      SCOPED_TRACE(::testing::Message() << "scale " << scale << ", " << to_string(precision));
      const LeastSquaresSummary scaled = solve_least_squares(A * scale, b * scale, names_of(3), nullptr, options);
      ASSERT_EQ(scaled.termination, Termination::success) << scaled.message;
      for (std::size_t j = 0; j < 3; ++j) {
        const ParameterEstimate& mine = scaled.parameters[j];
        const ParameterEstimate& theirs = reference.parameters[j];
        EXPECT_LT(relative_error(mine.value, theirs.value), tolerance);
        ASSERT_TRUE(std::isfinite(mine.standard_error) && mine.standard_error > 0) << mine.standard_error;
        EXPECT_LT(relative_error(mine.standard_error / mine.value, theirs.standard_error / theirs.value), tolerance);
      }
      EXPECT_LT(relative_error(scaled.r_squared, reference.r_squared), tolerance);
      EXPECT_LT(relative_error(scaled.standard_error, reference.standard_error * scale), tolerance);
      const double shift = 2 * 80 * std::log(scale);
      EXPECT_NEAR(scaled.aic, reference.aic + shift, 1e-9 * std::abs(shift));
      EXPECT_NEAR(scaled.bic, reference.bic + shift, 1e-9 * std::abs(shift));
      // What a double cannot hold is named: G near 1e400 or 1e-600.
      const std::vector<std::string> named = unrepresentable_statistics(scaled);
      ASSERT_EQ(named.size(), 1u);
      EXPECT_NE(named[0].find(scale > 1 ? "above the largest double, shown as inf" : "below the smallest double, shown as 0"),
                std::string::npos) << named[0];
    }
  }
}

// Only the known side in other units (the parameters carry the units): every parameter scales,
// relative standard errors and R^2 do not.
TEST(LeastSquares, KnownSideScaleMovesOnlyTheParameters) {
  const Eigen::MatrixXd A = random_matrix(40, 2, 23);
  const Eigen::VectorXd b = A * Eigen::Vector2d(1, -1) + orthogonal_residual(A, 0.5, 24);
  const LeastSquaresSummary reference = solve_least_squares(A, b, names_of(2), nullptr, {});
  for (double scale : {1e250, 1e-250}) {
    const LeastSquaresSummary scaled = solve_least_squares(A, b * scale, names_of(2), nullptr, {});
    ASSERT_EQ(scaled.termination, Termination::success);
    for (std::size_t j = 0; j < 2; ++j) {
      EXPECT_LT(relative_error(scaled.parameters[j].value, reference.parameters[j].value * scale), 1e-13);
      EXPECT_LT(relative_error(scaled.parameters[j].standard_error, reference.parameters[j].standard_error * scale), 1e-12);
    }
    EXPECT_LT(relative_error(scaled.r_squared, reference.r_squared), 1e-13);
  }
}

TEST(LeastSquares, NoDegreesOfFreedomIsNamedAsNotFinite) {
  const Eigen::MatrixXd A = random_matrix(3, 3, 15);
  const LeastSquaresSummary summary = solve_least_squares(A, A * Eigen::Vector3d(1, 2, 3), names_of(3), nullptr, {});
  const std::vector<std::string> named = unrepresentable_statistics(summary);
  EXPECT_NE(std::find(named.begin(), named.end(), "the residual SD (NaN)"), named.end());
  EXPECT_NE(std::find(named.begin(), named.end(), "the standard error of `a1` (NaN)"), named.end());
}

// A Wampler1-like fit (degree 5 on x = 0..20, exact data): plain QR in double loses digits,
// refinement against the original rows recovers them, and extended precision all of them.
TEST(LeastSquares, RefinementRecoversDigitsOnAnIllConditionedPolynomial) {
  Eigen::MatrixXd A(21, 6);
  Eigen::VectorXd b(21);
  for (int i = 0; i < 21; ++i) {
    double power = 1;
    b(i) = 0;
    for (int k = 0; k < 6; ++k) {
      A(i, k) = power;
      b(i) += power;  // all parameters 1
      power *= i;
    }
  }
  const auto worst_error = [&](const LeastSquaresOptions& options) {
    const LeastSquaresSummary summary = solve_least_squares(A, b, names_of(6), nullptr, options);
    double worst = 0;
    for (const ParameterEstimate& estimate : summary.parameters) worst = std::max(worst, std::abs(estimate.value - 1));
    return worst;
  };
  LeastSquaresOptions plain;
  plain.precision = Precision::double_precision;
  plain.refinement_steps = 0;
  LeastSquaresOptions refined = plain;
  refined.refinement_steps = 2;
  LeastSquaresOptions extended;
  extended.precision = Precision::extended;
  const double plain_error = worst_error(plain), refined_error = worst_error(refined);
  EXPECT_GT(plain_error, 1e-12);  // the condition number (2.6e3 scaled) costs digits
  EXPECT_LT(refined_error, plain_error / 100);
  EXPECT_LT(refined_error, 1e-12);
  EXPECT_LT(worst_error(extended), 1e-15);
  const LeastSquaresSummary summary = solve_least_squares(A, b, names_of(6), nullptr, refined);
  EXPECT_GT(summary.refinement_steps_taken, 0);
  EXPECT_GT(summary.refinement_change, 1e-12);  // it did move the plain solution
}

TEST(LeastSquares, AutomaticPrecisionDependsOnProblemSize) {
  const Eigen::MatrixXd A = random_matrix(40, 3, 16);
  const Eigen::VectorXd b = A * Eigen::Vector3d(1, 1, 1) + orthogonal_residual(A, 1, 17);
  LeastSquaresOptions options;
  EXPECT_TRUE(solve_least_squares(A, b, names_of(3), nullptr, options).extended_precision_used);
  options.extended_work_limit = 40 * 9 - 1;
  const LeastSquaresSummary large = solve_least_squares(A, b, names_of(3), nullptr, options);
  EXPECT_FALSE(large.extended_precision_used);
  EXPECT_NE(large.arithmetic.find("automatic"), std::string::npos);
}

TEST(LeastSquares, CentringMapsParametersAndCovarianceBackExactly) {
  // y = b0 + b1 t + b2 t^2 with t = 1e4 + i/4: the raw columns are nearly collinear. Every number
  // is exact in double: the parameters are powers of two, and the residual is 2^-20 times the
  // discrete Chebyshev polynomial of degree 3 in s = i - 24.5 (20 s^3 - 7493 s, orthogonal to 1, s,
  // s^2 on these 50 points), so `truth` is the exact least-squares solution of the rows as stored.
  const int n = 50;
  Eigen::MatrixXd A(n, 3);
  Eigen::VectorXd b(n);
  const Eigen::Vector3d truth(5, -1.0 / 512, 1.0 / 4194304);
  long double G = 0;
  for (int i = 0; i < n; ++i) {
    const double t = 1e4 + 0.25 * i;
    const double s = i - 24.5;
    const double e = std::ldexp(20 * s * s * s - 7493 * s, -20);
    A(i, 0) = 1;
    A(i, 1) = t;
    A(i, 2) = t * t;
    b(i) = A.row(i).dot(truth) + e;
    G += static_cast<long double>(e) * e;
  }
  LeastSquaresOptions plain, centred;
  centred.center_columns = true;
  const LeastSquaresSummary a = solve_least_squares(A, b, {"1", "t", "t^2"}, nullptr, plain);
  const LeastSquaresSummary c = solve_least_squares(A, b, {"1", "t", "t^2"}, nullptr, centred);
  ASSERT_EQ(c.termination, Termination::success);
  EXPECT_TRUE(c.columns_centred);
  EXPECT_FALSE(a.columns_centred);
  EXPECT_LT(c.condition_after, a.condition_after / 100);
  for (std::size_t j = 0; j < 3; ++j) {
    EXPECT_LT(relative_error(c.parameters[j].value, truth(static_cast<Eigen::Index>(j))), 1e-13);
    EXPECT_LT(relative_error(a.parameters[j].value, truth(static_cast<Eigen::Index>(j))), 1e-13);
    EXPECT_LT(relative_error(c.parameters[j].standard_error, a.parameters[j].standard_error), 1e-8);
  }
  EXPECT_LT(relative_error(c.G, static_cast<double>(G)), 1e-13);
  EXPECT_LT(relative_error(a.G, static_cast<double>(G)), 1e-13);
  // In double, centring is what keeps the digits: compare with the uncentred double fit.
  LeastSquaresOptions plain_double = plain, centred_double = centred;
  plain_double.precision = centred_double.precision = Precision::double_precision;
  plain_double.refinement_steps = centred_double.refinement_steps = 0;
  const LeastSquaresSummary ad = solve_least_squares(A, b, {"1", "t", "t^2"}, nullptr, plain_double);
  const LeastSquaresSummary cd = solve_least_squares(A, b, {"1", "t", "t^2"}, nullptr, centred_double);
  EXPECT_LT(relative_error(cd.parameters[2].standard_error, c.parameters[2].standard_error),
            relative_error(ad.parameters[2].standard_error, c.parameters[2].standard_error));
}

TEST(LeastSquares, RSquaredIsCentredOnlyWithAConstantColumn) {
  const Eigen::MatrixXd x = random_matrix(30, 1, 19);
  Eigen::VectorXd y = 2 * x.col(0);
  std::mt19937 generator(20);
  std::normal_distribution<double> normal(0, 0.3);
  for (Eigen::Index i = 0; i < y.size(); ++i) y(i) += 1 + normal(generator);
  // No intercept: uncentred, SSR / (SSR + SSE) = 1 - G / sum y^2 (NIST NoInt convention).
  const LeastSquaresSummary no_intercept = solve_least_squares(x, y, {"x"}, nullptr, {});
  EXPECT_FALSE(no_intercept.r_squared_centred);
  EXPECT_NEAR(no_intercept.r_squared, 1 - no_intercept.G / y.squaredNorm(), 1e-13);
  // With an intercept: centred, 1 - G / sum (y - mean)^2; unless told otherwise.
  Eigen::MatrixXd A(30, 2);
  A.col(0).setOnes();
  A.col(1) = x.col(0);
  const LeastSquaresSummary with_intercept = solve_least_squares(A, y, {"1", "x"}, nullptr, {});
  EXPECT_TRUE(with_intercept.r_squared_centred);
  const double total = (y.array() - y.mean()).square().sum();
  EXPECT_NEAR(with_intercept.r_squared, 1 - with_intercept.G / total, 1e-13);
  LeastSquaresOptions uncentred;
  uncentred.intercept_in_r2 = false;
  const LeastSquaresSummary forced = solve_least_squares(A, y, {"1", "x"}, nullptr, uncentred);
  EXPECT_FALSE(forced.r_squared_centred);
  EXPECT_NEAR(forced.r_squared, 1 - forced.G / y.squaredNorm(), 1e-13);
}

TEST(LeastSquares, ReportsNameWhatWasDone) {
  const Eigen::MatrixXd A = random_matrix(20, 2, 21);
  const Eigen::VectorXd b = A * Eigen::Vector2d(1, 2) + orthogonal_residual(A, 0.1, 22);
  const LeastSquaresSummary summary = solve_least_squares(A, b, {"damping", "stiffness"}, nullptr, {});
  const std::string brief = summary.brief_report();
  EXPECT_EQ(brief.find('\n'), std::string::npos);
  EXPECT_NE(brief.find("success"), std::string::npos);
  const std::string full = summary.full_report();
  for (const char* expected : {"damping", "stiffness", "rank", "refinement", "scaling", "condition", "digits lost",
                               "sqrt(G/n)", "eq. 2-1.7"}) {
    EXPECT_NE(full.find(expected), std::string::npos) << expected << "\n" << full;
  }
}

// ---- TriangularAccumulator ----

struct WeightedProblem {
  Eigen::MatrixXd A;
  Eigen::VectorXd b, w;
};

WeightedProblem intercept_problem(int n, unsigned seed) {
  WeightedProblem problem;
  problem.A = random_matrix(n, 5, seed);
  problem.A.col(0).setOnes();
  problem.b = problem.A * Eigen::VectorXd::LinSpaced(5, -1, 3);
  std::mt19937 generator(seed + 1);
  std::normal_distribution<double> normal(0, 0.5);
  std::uniform_real_distribution<double> uniform(0.5, 1.5);
  problem.w.resize(n);
  for (int i = 0; i < n; ++i) {
    problem.b(i) += normal(generator);
    problem.w(i) = uniform(generator);
  }
  return problem;
}

void add_in_blocks(TriangularAccumulator& accumulator, const WeightedProblem& problem, Eigen::Index from,
                   Eigen::Index to, Eigen::Index block) {
  for (Eigen::Index start = from; start < to; start += block) {
    const Eigen::Index count = std::min(block, to - start);
    const Eigen::VectorXd w = problem.w.segment(start, count);
    ASSERT_TRUE(accumulator.add_rows(problem.A.middleRows(start, count), problem.b.segment(start, count), &w));
  }
}

void expect_same_fit(const LeastSquaresSummary& a, const LeastSquaresSummary& b, double tolerance) {
  ASSERT_EQ(a.termination, b.termination);
  EXPECT_EQ(a.n, b.n);
  EXPECT_EQ(a.rank, b.rank);
  for (std::size_t j = 0; j < a.parameters.size(); ++j) {
    EXPECT_LT(relative_error(a.parameters[j].value, b.parameters[j].value), tolerance) << j;
    EXPECT_LT(relative_error(a.parameters[j].standard_error, b.parameters[j].standard_error), tolerance) << j;
    EXPECT_LT(relative_error(a.parameters[j].ci_low, b.parameters[j].ci_low), tolerance) << j;
  }
  EXPECT_LT(relative_error(a.G, b.G), tolerance);
  EXPECT_LT(relative_error(a.residual_sd, b.residual_sd), tolerance);
  EXPECT_LT(relative_error(a.standard_error, b.standard_error), tolerance);
  EXPECT_LT(relative_error(a.r_squared, b.r_squared), tolerance);
  EXPECT_EQ(a.r_squared_centred, b.r_squared_centred);
  EXPECT_NEAR(a.aic, b.aic, tolerance * std::abs(a.aic));
  EXPECT_NEAR(a.bic, b.bic, tolerance * std::abs(a.bic));
  EXPECT_LT(relative_error(a.condition_after, b.condition_after), 1e-6);
  EXPECT_LT(relative_error(a.condition_before, b.condition_before), 1e-6);
}

TEST(TriangularAccumulator, AgreesWithTheDirectSolve) {
  const WeightedProblem problem = intercept_problem(1000, 23);
  const std::vector<std::string> names = names_of(5);
  TriangularAccumulator accumulator(5);
  add_in_blocks(accumulator, problem, 0, 1000, 37);
  EXPECT_EQ(accumulator.rows(), 1000u);
  const LeastSquaresSummary streamed = accumulator.solve(names, {});
  const LeastSquaresSummary direct = solve_least_squares(problem.A, problem.b, names, &problem.w, {});
  ASSERT_EQ(direct.termination, Termination::success);
  expect_same_fit(streamed, direct, 1e-10);
  EXPECT_TRUE(streamed.residuals.empty());
  EXPECT_EQ(direct.residuals.size(), 1000u);
  // Second pass for residuals, block by block.
  const Eigen::VectorXd residuals = TriangularAccumulator::residuals_of(problem.A, problem.b, streamed);
  for (Eigen::Index i = 0; i < residuals.size(); ++i) {
    EXPECT_NEAR(residuals(i), direct.residuals[static_cast<std::size_t>(i)], 1e-10);
  }
}

TEST(TriangularAccumulator, MergedAccumulatorsEqualOne) {
  const WeightedProblem problem = intercept_problem(600, 24);
  const std::vector<std::string> names = names_of(5);
  TriangularAccumulator whole(5), first(5), second(5);
  add_in_blocks(whole, problem, 0, 600, 100);
  add_in_blocks(first, problem, 0, 250, 64);
  add_in_blocks(second, problem, 250, 600, 50);
  ASSERT_TRUE(first.merge(second));
  EXPECT_EQ(first.rows(), 600u);
  expect_same_fit(first.solve(names, {}), whole.solve(names, {}), 1e-11);
  TriangularAccumulator other_width(4);
  std::string why;
  EXPECT_FALSE(first.merge(other_width, &why));
  EXPECT_FALSE(why.empty());
}

TEST(TriangularAccumulator, RejectedBlockMakesTheFitInvalid) {
  const WeightedProblem problem = intercept_problem(50, 25);
  TriangularAccumulator accumulator(5);
  add_in_blocks(accumulator, problem, 0, 50, 10);
  Eigen::MatrixXd bad = problem.A.topRows(3);
  bad(1, 2) = std::numeric_limits<double>::quiet_NaN();
  std::string why;
  EXPECT_FALSE(accumulator.add_rows(bad, problem.b.head(3), nullptr, &why));
  EXPECT_FALSE(why.empty());
  EXPECT_FALSE(accumulator.add_rows(problem.A.leftCols(4), problem.b, nullptr));
  EXPECT_EQ(accumulator.rows(), 50u);  // nothing of the bad blocks was folded
  EXPECT_EQ(accumulator.rejected_blocks(), 2u);
  const LeastSquaresSummary summary = accumulator.solve(names_of(5), {});
  EXPECT_EQ(summary.termination, Termination::invalid_input);
  EXPECT_NE(summary.message.find("rejected"), std::string::npos);
}

TEST(TriangularAccumulator, NamesDependentColumnsAndCountsRows) {
  Eigen::MatrixXd A = random_matrix(40, 3, 26);
  A.col(2) = 3 * A.col(0);
  const Eigen::VectorXd b = A.col(0) + A.col(1);
  TriangularAccumulator accumulator(3);
  ASSERT_TRUE(accumulator.add_rows(A, b, nullptr));
  const LeastSquaresSummary summary = accumulator.solve({"p", "q", "3p"}, {});
  ASSERT_EQ(summary.termination, Termination::rank_deficient);
  ASSERT_EQ(summary.dependent_groups.size(), 1u);
  std::vector<std::string> group = summary.dependent_groups[0];
  std::sort(group.begin(), group.end());
  EXPECT_EQ(group, (std::vector<std::string>{"3p", "p"}));
  TriangularAccumulator empty(3);
  EXPECT_EQ(empty.solve({"p", "q", "r"}, {}).termination, Termination::too_few_rows);
}

}  // namespace
}  // namespace sidc
