// Cumulative Simpson and trapezoid integration: exactness at every sample (even and odd), nested
// use, measured order of convergence, short signals, and smoothing before integration.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "runtime/operators/simpson.hpp"

namespace sidc {
namespace {

std::vector<double> sampled(std::size_t n, double t0, double delta, double (*f)(double)) {
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i) y[i] = f(t0 + static_cast<double>(i) * delta);
  return y;
}

double quadratic(double t) { return 1.5 - 2 * t + 3 * t * t; }
double quadratic_integral(double t) { return 1.5 * t - t * t + t * t * t; }
double cubic(double t) { return -0.5 + t - 1.5 * t * t + 2 * t * t * t; }
double cubic_integral(double t) { return -0.5 * t + t * t / 2 - 0.5 * t * t * t + 0.5 * t * t * t * t; }

TEST(CumulativeSimpson, ExactForQuadraticsAndCubicsAtEverySample) {
  const double t0 = -0.7;
  const double delta = 0.13;
  for (const std::size_t n : {3u, 4u, 5u, 10u, 11u}) {
    const auto iq = cumulative_simpson(sampled(n, t0, delta, quadratic), delta);
    ASSERT_EQ(iq.size(), n);
    EXPECT_EQ(iq[0], 0.0);
    for (std::size_t i = 0; i < n; ++i)
      EXPECT_NEAR(iq[i], quadratic_integral(t0 + static_cast<double>(i) * delta) - quadratic_integral(t0), 1e-14)
          << "n " << n << " i " << i;
    if (n < 4) continue;  // a cubic needs four samples for its odd intervals
    const auto ic = cumulative_simpson(sampled(n, t0, delta, cubic), delta);
    for (std::size_t i = 0; i < n; ++i)
      EXPECT_NEAR(ic[i], cubic_integral(t0 + static_cast<double>(i) * delta) - cubic_integral(t0), 1e-14)
          << "n " << n << " i " << i;
  }
}

// int(int(f)) by repeated application: the first integral of a quadratic is a cubic, which the
// second application integrates exactly, at even and odd samples alike. (The double integral of a
// cubic is a quintic and no Simpson-type rule integrates its quartic integrand exactly.)
TEST(CumulativeSimpson, NestedIntegrationOfAQuadraticIsExact) {
  const double delta = 0.05;
  const std::size_t n = 21;
  const auto once = cumulative_simpson(sampled(n, 0.0, delta, quadratic), delta);
  const auto twice = cumulative_simpson(once, delta);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * delta;
    const double exact = 0.75 * t * t - t * t * t / 3 + t * t * t * t / 4;  // integral of 1.5 t - t^2 + t^3
    EXPECT_NEAR(twice[i], exact, 1e-14) << "i " << i;
  }
}

double smooth_function(double t) { return std::exp(std::sin(3 * t)); }

// The largest error over all samples of a cumulative integral of exp(sin 3t) on [0, 2].
double max_error(std::size_t intervals, bool trapezoid) {
  // Reference: Simpson with 64 times as many intervals; its error is negligible next to the coarse one.
  const double length = 2.0;
  const double delta = length / static_cast<double>(intervals);
  const auto f = sampled(intervals + 1, 0.0, delta, smooth_function);
  const auto integral = trapezoid ? cumulative_trapezoid(f, delta) : cumulative_simpson(f, delta);
  const std::size_t refine = 64;
  const auto fine_f = sampled(intervals * refine + 1, 0.0, delta / refine, smooth_function);
  const auto fine = cumulative_simpson(fine_f, delta / refine);
  double worst = 0;
  for (std::size_t i = 0; i <= intervals; ++i) worst = std::max(worst, std::fabs(integral[i] - fine[i * refine]));
  return worst;
}

double measured_order(std::size_t coarse, std::size_t fine, bool trapezoid) {
  return std::log(max_error(coarse, trapezoid) / max_error(fine, trapezoid)) /
         std::log(static_cast<double>(fine) / static_cast<double>(coarse));
}

// At coarse steps the odd samples' single-interval term (local error O(h^5) with a large
// constant) dominates and the error falls faster than h^4; from about 80 intervals on, the
// composite-Simpson error O(h^4) of the even samples takes over.
TEST(CumulativeSimpson, FourthOrderConvergenceMeasured) {
  for (const auto& [coarse, fine] : {std::pair<std::size_t, std::size_t>{160, 320}, {161, 321}, {40, 80}, {41, 81}}) {
    const double order = measured_order(coarse, fine, false);
    EXPECT_GT(order, 3.8) << coarse << " -> " << fine << " intervals";
    if (coarse >= 160) {
      EXPECT_LT(order, 4.3) << coarse << " -> " << fine << " intervals";
    }
  }
}

TEST(CumulativeTrapezoid, ExactForLinesAndSecondOrder) {
  const double delta = 0.1;
  const auto line = cumulative_trapezoid(std::vector<double>{1, 1.2, 1.4, 1.6}, delta);
  for (std::size_t i = 0; i < 4; ++i) {
    const double t = static_cast<double>(i) * delta;
    EXPECT_NEAR(line[i], t + t * t, 1e-15);
  }
  const double order = measured_order(20, 40, true);
  EXPECT_NEAR(order, 2.0, 0.2);
}

TEST(CumulativeSimpson, ShortSignals) {
  EXPECT_TRUE(cumulative_simpson(std::vector<double>{}, 0.1).empty());
  EXPECT_EQ(cumulative_simpson(std::vector<double>{5}, 0.1), std::vector<double>{0.0});
  const auto two = cumulative_simpson(std::vector<double>{1, 3}, 0.5);
  EXPECT_DOUBLE_EQ(two[1], 1.0);
}

TEST(CumulativeIntegral, SmoothingBeforeIntegrating) {
  // Smoothing with a 7-point cubic keeps a cubic as it is (shortened edges), so the integral stays exact.
  const double delta = 0.05;
  const auto f = sampled(31, 0.0, delta, cubic);
  IntegrationOptions options;
  options.smoothing_window = 7;
  options.smoothing_polyorder = 3;
  auto result = cumulative_integral(f, delta, options);
  ASSERT_TRUE(std::holds_alternative<std::vector<double>>(result));
  const auto& integral = std::get<std::vector<double>>(result);
  for (std::size_t i = 0; i < f.size(); ++i)
    EXPECT_NEAR(integral[i], cubic_integral(static_cast<double>(i) * delta) - cubic_integral(0), 1e-13) << i;

  // On noisy samples smoothing brings the integrand closer to the truth.
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 0.05);
  auto noisy = sampled(201, 0.0, 0.01, smooth_function);
  for (double& v : noisy) v += noise(rng);
  IntegrationOptions smooth;
  smooth.smoothing_window = 11;
  smooth.smoothing_polyorder = 2;
  const auto raw = std::get<std::vector<double>>(cumulative_integral(noisy, 0.01));
  const auto filtered = std::get<std::vector<double>>(cumulative_integral(noisy, 0.01, smooth));
  const auto truth = cumulative_simpson(sampled(201, 0.0, 0.01, smooth_function), 0.01);
  double raw_error = 0, filtered_error = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    raw_error += std::pow(raw[i] - truth[i], 2);
    filtered_error += std::pow(filtered[i] - truth[i], 2);
  }
  EXPECT_LT(filtered_error, raw_error);

  IntegrationOptions trapezoid;
  trapezoid.rule = IntegrationOptions::Rule::trapezoid;
  EXPECT_EQ(std::get<std::vector<double>>(cumulative_integral(noisy, 0.01, trapezoid)),
            cumulative_trapezoid(noisy, 0.01));
}

TEST(CumulativeIntegral, InvalidRequestsAreRefused) {
  const std::vector<double> f(10, 1.0);
  EXPECT_TRUE(std::holds_alternative<Diagnostic>(cumulative_integral(f, 0.0)));
  IntegrationOptions even;
  even.smoothing_window = 4;
  EXPECT_TRUE(std::holds_alternative<Diagnostic>(cumulative_integral(f, 0.1, even)));
  IntegrationOptions wide;
  wide.smoothing_window = 11;
  auto too_short = cumulative_integral(f, 0.1, wide);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(too_short));
  EXPECT_EQ(std::get<Diagnostic>(too_short).code, "signal-too-short");
}

}  // namespace
}  // namespace sidc
