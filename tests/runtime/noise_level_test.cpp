// The noise level estimate (runtime/operators/noise_level.hpp) on synthetic signals of known
// noise: several shapes and frequencies, noise from 0 to 20% of the spread, a constant, an exact
// polynomial, outliers, and a record long enough to be read in chunks.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "runtime/operators/noise_level.hpp"
#include "support/sampled_signal.hpp"

namespace sidc {
namespace {

using testing::sampled;
using testing::with_noise;

struct Shape {
  const char* name;
  std::function<double(double)> f;
};

const std::vector<Shape>& shapes() {
  static const std::vector<Shape> s{
      {"slow sine", [](double t) { return std::sin(0.5 * t); }},
      {"two tones", [](double t) { return std::sin(1.3 * t) + 0.5 * std::sin(3.1 * t); }},
      {"fast sine (12 samples a period)", [](double t) { return std::sin(2 * M_PI * t / 0.12); }},
      {"damped oscillation", [](double t) { return std::exp(-0.2 * t) * std::cos(4 * t); }},
      {"cubic trend", [](double t) { return 0.01 * t * t * t - 0.3 * t; }},
      {"kinked (|sin|)", [](double t) { return std::abs(std::sin(t)); }},
  };
  return s;
}

TEST(NoiseLevel, RecoversTheNoiseOfEveryShapeAndLevel) {
  for (const auto& shape : shapes()) {
    const auto clean = sampled(4001, 0.01, shape.f);
    const double spread = estimate_noise_level(clean).spread;
    for (double level : {1e-3, 1e-2, 5e-2, 0.2}) {
      const double sigma = level * spread;
      const auto noisy = with_noise(clean, sigma, 7);
      const NoiseLevel n = estimate_noise_level(noisy);
      // The MAD of 4000 differences: a few % of sampling error, plus a share of the smooth part.
      EXPECT_NEAR(n.sigma / sigma, 1.0, 0.1) << shape.name << " at " << level;
      EXPECT_FALSE(n.constant);
      EXPECT_EQ(n.samples, noisy.size());
    }
  }
}

// Scale-invariant: the same record in units of 1e200 or 1e-200 (issue 19: its spread was inf).
TEST(NoiseLevel, TheUnitOfTheRecordDoesNotMatter) {
  const auto noisy = with_noise(sampled(4001, 0.01, shapes().front().f), 0.01, 11);
  const NoiseLevel one = estimate_noise_level(noisy);
  for (double unit : {1e200, 1e-200}) {
    std::vector<double> scaled = noisy;
    for (double& v : scaled) v *= unit;
    const NoiseLevel n = estimate_noise_level(scaled);
    EXPECT_NEAR(n.spread / unit, one.spread, 1e-12 * one.spread) << unit;
    EXPECT_NEAR(n.sigma / unit, one.sigma, 1e-12 * one.sigma) << unit;
    EXPECT_NEAR(n.relative(), one.relative(), 1e-12) << unit;
    EXPECT_EQ(n.difference_order, one.difference_order) << unit;
  }
}

TEST(NoiseLevel, NoNoiseGivesAVerySmallLevel) {
  for (const auto& shape : shapes()) {
    if (std::string(shape.name).find("fast") != std::string::npos) continue;  // 12 samples a period: an upper bound only
    const NoiseLevel n = estimate_noise_level(sampled(2001, 0.01, shape.f));
    EXPECT_LT(n.relative(), 1e-5) << shape.name;
  }
  // Coarsely sampled: still far below the signal.
  EXPECT_LT(estimate_noise_level(sampled(2001, 0.01, shapes()[2].f)).relative(), 0.05);
}

TEST(NoiseLevel, AConstantSignalHasNoiseZero) {
  const NoiseLevel n = estimate_noise_level(std::vector<double>(500, 3.25));
  EXPECT_TRUE(n.constant);
  EXPECT_EQ(n.sigma, 0.0);
  EXPECT_EQ(n.spread, 0.0);
  EXPECT_EQ(n.relative(), 0.0);
  EXPECT_FALSE(n.exceeds_variation());
}

TEST(NoiseLevel, AnExactLineHasNoiseZero) {
  const NoiseLevel n = estimate_noise_level(sampled(300, 1.0, [](double t) { return 2 * t - 5; }));
  EXPECT_FALSE(n.constant);
  EXPECT_EQ(n.sigma, 0.0);
}

TEST(NoiseLevel, PureNoiseExceedsItsVariation) {
  const NoiseLevel n = estimate_noise_level(with_noise(std::vector<double>(5000, 1.0), 0.3, 3));
  EXPECT_NEAR(n.sigma, 0.3, 0.03);
  EXPECT_TRUE(n.exceeds_variation());
  // A signal with 1% noise does not.
  const auto clean = sampled(2000, 0.01, shapes()[1].f);
  EXPECT_FALSE(estimate_noise_level(with_noise(clean, 0.01, 3)).exceeds_variation());
}

TEST(NoiseLevel, AFewOutliersDoNotRaiseIt) {
  auto y = with_noise(sampled(4000, 0.01, shapes()[0].f), 1e-3, 11);
  for (std::size_t i = 100; i < y.size(); i += 400) y[i] += 5.0;  // 10 spikes
  EXPECT_NEAR(estimate_noise_level(y).sigma, 1e-3, 2e-4);
}

TEST(NoiseLevel, ALongRecordIsReadInChunks) {
  const auto y = with_noise(sampled(1'000'000, 1e-4, shapes()[1].f), 2e-3, 5);
  const NoiseLevel n = estimate_noise_level(y);
  EXPECT_EQ(n.samples, y.size());
  EXPECT_NEAR(n.sigma, 2e-3, 1e-4);
}

TEST(NoiseLevel, TooShortSignals) {
  EXPECT_EQ(estimate_noise_level(std::vector<double>{}).sigma, 0.0);
  const NoiseLevel two = estimate_noise_level(std::vector<double>{1.0, 2.0});
  EXPECT_EQ(two.difference_order, 0);
  EXPECT_EQ(two.sigma, 0.0);
}

}  // namespace
}  // namespace sidc
