// runtime/select/size_rule: the relative-G elbow on G sequences shaped like a noise-free record
// (G falls by orders of magnitude at the true size, then a little per extra term that fits the
// operators' smooth error) and a noisy one, and the drift test on columns that are and are not
// nearly a polynomial in t, before and after integration.
#include "runtime/select/size_rule.hpp"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace sidc {
namespace {

TEST(RelativeGElbow, NoiseFreeRecordStopsWhereGFallsByOrdersOfMagnitude) {
  // Extra terms after the true size (index 3) still halve G: AIC, BIC and CV would keep them.
  const ElbowResult e = relative_g_elbow({9062, 1389, 348, 1.7e-9, 1.0e-9, 0.6e-9, 0.4e-9});
  EXPECT_EQ(e.index, 3);
  EXPECT_TRUE(std::isnan(e.left[0]));
  EXPECT_LT(e.left[3], 0.1);
  EXPECT_GT(e.left[2], 0.9);
}

TEST(RelativeGElbow, NoisyRecordStopsAtTheNoiseFloor) {
  const ElbowResult e = relative_g_elbow({100, 1, 0.0105, 0.0101, 0.01005, 0.0100});
  EXPECT_EQ(e.index, 2);
}

TEST(RelativeGElbow, WithoutAnElbowTheLargestSizeIsTaken) {
  // G halves at every size: no step closes 90% of the remaining distance before the last.
  const ElbowResult e = relative_g_elbow({1, 0.5, 0.25, 0.125, 0.0625});
  EXPECT_EQ(e.index, 4);
  EXPECT_NEAR(e.left[1], 0.75, 1e-12);
}

TEST(RelativeGElbow, ShareAndExactFitsAndShortLists) {
  EXPECT_EQ(relative_g_elbow({100, 10, 1, 0.5, 0.25}, 0.5).index, 2);  // 10 -> 1 leaves log 4 / log 40 = 0.38
  EXPECT_EQ(relative_g_elbow({100, 10, 1, 0.5, 0.25}).index, 4);
  EXPECT_EQ(relative_g_elbow({100, 1e-3, 0, 0}).index, 2);  // G = 0 held at the smallest normal number
  EXPECT_EQ(relative_g_elbow({5}).index, -1);
  EXPECT_EQ(relative_g_elbow({}).index, -1);
}

Eigen::VectorXd sampled(int n, double (*f)(double)) {
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v(i) = f(0.01 * i);
  return v;
}

// Cumulative sum: an integral up to the step factor.
Eigen::VectorXd integrated(const Eigen::VectorXd& v) {
  Eigen::VectorXd out(v.size());
  double sum = 0;
  for (Eigen::Index i = 0; i < v.size(); ++i) out(i) = sum += v(i);
  return out;
}

TEST(DriftTest, PolynomialShareOfLinesSinesAndConstants) {
  const int n = 4000;
  Eigen::MatrixXd m(n, 4);
  m.col(0) = sampled(n, [](double t) { return 3 - 0.5 * t * t; });
  m.col(1) = sampled(n, [](double t) { return std::sin(2 * std::numbers::pi * t); });
  m.col(2) = Eigen::VectorXd::Constant(n, 7);
  m.col(3) = Eigen::VectorXd::Zero(n);
  const auto share = polynomial_energy_share(m, 2);
  EXPECT_NEAR(share[0], 1, 1e-12);
  EXPECT_LT(share[1], 0.01);
  EXPECT_NEAR(share[2], 1, 1e-12);
  EXPECT_TRUE(std::isnan(share[3]));
}

TEST(DriftTest, ThePendulumsCosineIsAnAbsorberAndAHalfWaveDamperIsNot) {
  // theta = 0.3 sin(t): cos(theta) is 99.99% constant; y' restricted to y' <= 0 has a mean too,
  // but only 40% of its sum of squares is a line. Integrated once and twice, the verdict is the
  // same however long the record (its integral would look like a ramp on a long one).
  const int n = 20000;
  Eigen::MatrixXd m(n, 2);
  m.col(0) = sampled(n, [](double t) { return std::cos(0.3 * std::sin(t)); });
  m.col(1) = sampled(n, [](double t) { return std::min(0.0, std::cos(t)); });
  for (int integrations = 0; integrations <= 2; ++integrations) {
    Eigen::MatrixXd column = m;
    for (int i = 0; i < integrations; ++i)
      for (int c = 0; c < 2; ++c) column.col(c) = integrated(column.col(c));
    const auto share = operation_line_share(column, integrations);
    EXPECT_GT(share[0], kDriftAbsorberShare) << integrations;
    EXPECT_LT(share[1], 0.5) << integrations;
  }
  // On the integrated column itself the damper would pass for a drift absorber.
  Eigen::MatrixXd once(n, 1);
  once.col(0) = integrated(m.col(1));
  EXPECT_GT(polynomial_energy_share(once, 2)[0], 0.999);
}

}  // namespace
}  // namespace sidc
