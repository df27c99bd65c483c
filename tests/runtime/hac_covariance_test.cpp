// runtime/solve/hac_covariance: the Newey-West intervals hold the truth at their level where the
// classical ones do not (autocorrelated errors and regressors), agree with the classical ones on
// independent rows, never let a lag cross a segment, and say why when they are not computed.
#include "runtime/solve/hac_covariance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "runtime/solve/least_squares.hpp"

namespace sidc {
namespace {

struct Problem {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
};

// y = 2 + 0.5 x + e with x and e each AR(1) with coefficient rho (rho = 0: independent rows).
Problem ar1_regression(std::mt19937_64& rng, int n, double rho) {
  std::normal_distribution<double> normal;
  Problem p{Eigen::MatrixXd(n, 2), Eigen::VectorXd(n)};
  double x = normal(rng), e = normal(rng);
  for (int i = 0; i < n; ++i) {
    x = rho * x + normal(rng);
    e = rho * e + normal(rng);
    p.A(i, 0) = 1;
    p.A(i, 1) = x;
    p.b(i) = 2 + 0.5 * x + e;
  }
  return p;
}

LeastSquaresSummary solve(const Problem& p) {
  LeastSquaresOptions options;
  options.precision = Precision::double_precision;
  return solve_least_squares(p.A, p.b, {"a", "b"}, nullptr, options);
}

// How often, over `runs` records, the classical and the HAC 95% intervals of the slope hold 0.5.
std::pair<double, double> slope_coverage(double rho, int runs, int n) {
  std::mt19937_64 rng(20261127);
  int classical = 0, hac = 0;
  for (int k = 0; k < runs; ++k) {
    const Problem p = ar1_regression(rng, n, rho);
    const LeastSquaresSummary s = solve(p);
    const HacEstimate h = hac_covariance(p.A, s.residuals, nullptr, {0}, s);
    EXPECT_TRUE(h.computed) << h.note;
    if (!h.computed) continue;
    classical += s.parameters[1].ci_low <= 0.5 && 0.5 <= s.parameters[1].ci_high;
    hac += h.ci_low[1] <= 0.5 && 0.5 <= h.ci_high[1];
  }
  return {static_cast<double>(classical) / runs, static_cast<double>(hac) / runs};
}

TEST(HacCovariance, HoldsTheTruthWhereTheClassicalIntervalsDoNot) {
  // Both the regressor and the error AR(1) with 0.8: the slope's true variance is (1 + 0.64) /
  // (1 - 0.64) = 4.6 times the classical one, so the classical 95% interval holds about 65%.
  const auto [classical, hac] = slope_coverage(0.8, 300, 400);
  std::printf("coverage rho 0.8: classical %.3f hac %.3f\n", classical, hac);
  EXPECT_LT(classical, 0.80);
  EXPECT_GE(hac, 0.86);
  EXPECT_LE(hac, 0.99);
}

TEST(HacCovariance, AgreesWithTheClassicalIntervalsOnIndependentRows) {
  const auto [classical, hac] = slope_coverage(0.0, 300, 400);
  std::printf("coverage rho 0: classical %.3f hac %.3f\n", classical, hac);
  EXPECT_NEAR(classical, 0.95, 0.04);
  EXPECT_NEAR(hac, 0.95, 0.05);
  std::mt19937_64 rng(7);
  const Problem p = ar1_regression(rng, 4000, 0.0);
  const LeastSquaresSummary s = solve(p);
  const HacEstimate h = hac_covariance(p.A, s.residuals, nullptr, {0}, s);
  ASSERT_TRUE(h.computed);
  EXPECT_LT(std::abs(h.lag1_autocorrelation), h.band);
  for (int j = 0; j < 2; ++j) EXPECT_NEAR(h.standard_errors[j] / s.parameters[j].standard_error, 1.0, 0.15);
}

TEST(HacCovariance, SaysTheRowsAreCorrelatedAndWidensByTheLongRunFactor) {
  std::mt19937_64 rng(11);
  const Problem p = ar1_regression(rng, 20000, 0.8);
  const LeastSquaresSummary s = solve(p);
  const HacEstimate h = hac_covariance(p.A, s.residuals, nullptr, {0}, s);
  ASSERT_TRUE(h.computed);
  EXPECT_GT(h.lag1_autocorrelation, h.band);
  EXPECT_NEAR(h.lag1_autocorrelation, 0.8, 0.03);
  // The slope's standard error: sqrt(4.6) = 2.13 times the classical one.
  EXPECT_NEAR(h.standard_errors[1] / s.parameters[1].standard_error, std::sqrt(1.64 / 0.36), 0.35);
}

TEST(HacCovariance, NoLagCrossesASegment) {
  // Two records of one equation: swapping them changes no row's neighbours, so nothing may change;
  // a lag across the boundary would pair the last row of one with the first of the other.
  std::mt19937_64 rng(3);
  const Problem first = ar1_regression(rng, 300, 0.9), second = ar1_regression(rng, 500, 0.9);
  Problem joined{Eigen::MatrixXd(800, 2), Eigen::VectorXd(800)}, swapped{Eigen::MatrixXd(800, 2), Eigen::VectorXd(800)};
  joined.A << first.A, second.A;
  joined.b << first.b, second.b;
  swapped.A << second.A, first.A;
  swapped.b << second.b, first.b;
  const LeastSquaresSummary s1 = solve(joined), s2 = solve(swapped);
  const HacEstimate h1 = hac_covariance(joined.A, s1.residuals, nullptr, {0, 300}, s1);
  const HacEstimate h2 = hac_covariance(swapped.A, s2.residuals, nullptr, {0, 500}, s2);
  ASSERT_TRUE(h1.computed && h2.computed);
  for (int j = 0; j < 2; ++j) EXPECT_NEAR(h1.standard_errors[j], h2.standard_errors[j], 1e-9 * h1.standard_errors[j]);
  // Told as one segment, the boundary's pair enters: the answer moves.
  const HacEstimate one = hac_covariance(joined.A, s1.residuals, nullptr, {0}, s1);
  ASSERT_TRUE(one.computed);
  EXPECT_GT(std::abs(one.standard_errors[1] - h1.standard_errors[1]), 1e-9 * h1.standard_errors[1]);
}

TEST(HacCovariance, WeightsEnterAsTheClassicalCovarianceDoes) {
  // Weights of 2 on every row scale the problem, not the answer: the same intervals.
  std::mt19937_64 rng(5);
  const Problem p = ar1_regression(rng, 1000, 0.5);
  const Eigen::VectorXd twos = Eigen::VectorXd::Constant(1000, 2.0);
  LeastSquaresOptions options;
  options.precision = Precision::double_precision;
  const LeastSquaresSummary plain = solve(p), weighted = solve_least_squares(p.A, p.b, {"a", "b"}, &twos, options);
  const HacEstimate h1 = hac_covariance(p.A, plain.residuals, nullptr, {0}, plain);
  const HacEstimate h2 = hac_covariance(p.A, weighted.residuals, &twos, {0}, weighted);
  ASSERT_TRUE(h1.computed && h2.computed);
  for (int j = 0; j < 2; ++j) EXPECT_NEAR(h1.standard_errors[j], h2.standard_errors[j], 1e-8 * h1.standard_errors[j]);
}

TEST(HacCovariance, SaysWhyWhenNotComputed) {
  std::mt19937_64 rng(1);
  const Problem p = ar1_regression(rng, 5, 0.0);
  const LeastSquaresSummary s = solve(p);
  const HacEstimate few = hac_covariance(p.A, s.residuals, nullptr, {0}, s);
  EXPECT_FALSE(few.computed);
  EXPECT_NE(few.note.find("too few rows"), std::string::npos) << few.note;

  Problem dependent = ar1_regression(rng, 100, 0.0);
  dependent.A.col(1) = 3 * dependent.A.col(0);
  const LeastSquaresSummary d = solve(dependent);
  const HacEstimate none = hac_covariance(dependent.A, d.residuals, nullptr, {0}, d);
  EXPECT_FALSE(none.computed);
  EXPECT_FALSE(none.note.empty());
}

}  // namespace
}  // namespace sidc
