// Isolated outliers (runtime/records/isolated_outliers.hpp): glitches put into smooth signals of
// known noise are found at their samples and replaced by a value within the noise of the truth;
// clean signals of many shapes and noise levels, noise-free ones, a step, a kink, a burst and a
// coarsely quantised signal give none; a record long enough for the sampled scale is read in full.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "runtime/records/isolated_outliers.hpp"
#include "support/sampled_signal.hpp"

namespace sidc::outliers_test {

using testing::sampled;
using testing::with_noise;

double oscillation(double t) { return std::sin(0.7 * t) + 0.4 * std::sin(2.3 * t + 0.5); }

std::vector<std::size_t> samples_of(const std::vector<IsolatedOutlier>& found) {
  std::vector<std::size_t> out;
  for (const auto& o : found) out.push_back(o.sample);
  return out;
}

TEST(IsolatedOutliers, GlitchesAreFoundAtTheirSamplesAndReplacedWithinTheNoise) {
  const double sigma = 0.01;
  const std::vector<double> truth = sampled(4000, 0.05, oscillation);
  std::vector<double> y = with_noise(truth, sigma, 7);
  const std::vector<std::size_t> glitches{5, 700, 1063, 2500, 3994};
  const std::vector<double> sizes{0.3, -0.5, 2.0, -0.15, 0.4};  // 15 to 200 noise levels
  for (std::size_t k = 0; k < glitches.size(); ++k) y[glitches[k]] += sizes[k];
  const std::vector<double> t = sampled(4000, 0.05, [](double s) { return s; });
  double z = 0;
  const auto found = find_isolated_outliers(y, t, &z);
  EXPECT_EQ(samples_of(found), glitches);
  EXPECT_NEAR(z, 4.71, 0.01);  // Phi^-1(1 - 0.005 / 3994)
  for (const auto& o : found) {
    EXPECT_EQ(o.time, t[o.sample]);
    EXPECT_EQ(o.value, y[o.sample]);
    // The quadratic through six noisy neighbours: within 4 of its s.d. (sqrt(0.5) sigma) of the truth.
    EXPECT_NEAR(o.replacement, truth[o.sample], 4 * std::sqrt(0.5) * sigma) << "sample " << o.sample;
    EXPECT_GT(o.size, z);
  }
}

TEST(IsolatedOutliers, CleanSignalsHaveNone) {
  const std::vector<std::function<double(double)>> shapes{
      oscillation,
      [](double t) { return std::exp(-0.05 * t) * std::cos(3 * t); },
      [](double t) { return 0.001 * t * t * t - 0.2 * t; },
      [](double t) { return std::sin(2 * M_PI * t / 0.6); },  // 12 samples a period
      [](double t) { return std::tanh(t - 50) + 0.1 * std::sin(t); },
  };
  int signals = 0;
  for (std::size_t s = 0; s < shapes.size(); ++s)
    for (const double sigma : {0.0, 1e-4, 1e-3, 1e-2, 5e-2})
      for (unsigned seed = 1; seed <= 4; ++seed) {
        const auto y = with_noise(sampled(2000, 0.05, shapes[s]), sigma, seed);
        EXPECT_TRUE(find_isolated_outliers(y).empty()) << "shape " << s << ", noise " << sigma << ", seed " << seed;
        ++signals;
      }
  EXPECT_EQ(signals, 100);
}

TEST(IsolatedOutliers, StepsKinksBurstsAndQuantisedSignalsAreNotIsolatedOutliers) {
  // A step between two samples: two neighbouring residuals of opposite sign, no spike.
  EXPECT_TRUE(find_isolated_outliers(with_noise(sampled(1000, 0.1, [](double t) { return std::sin(t) + (t > 50.02 ? 1.0 : 0.0); }), 1e-3, 3)).empty());
  // A kink (a jump of the slope) and a jump of the second derivative.
  EXPECT_TRUE(find_isolated_outliers(with_noise(sampled(1000, 0.1, [](double t) { return std::abs(t - 50.05); }), 1e-3, 4)).empty());
  EXPECT_TRUE(find_isolated_outliers(sampled(1000, 0.1, [](double t) { return t > 50.05 ? (t - 50.05) * (t - 50.05) : 0.0; })).empty());
  // A burst of three bad samples in a row is no isolated sample: left for the user to see.
  auto burst = with_noise(sampled(1000, 0.1, [](double t) { return std::sin(t); }), 1e-3, 5);
  for (std::size_t i = 500; i < 503; ++i) burst[i] += 0.5;
  EXPECT_TRUE(find_isolated_outliers(burst).empty());
  // A slow signal read by a coarse converter: most residuals exactly 0, one quantum of dither.
  auto coarse = sampled(3000, 0.01, [](double t) { return 0.3 * std::sin(0.2 * t); });
  for (double& v : coarse) v = std::round(v / 0.01) * 0.01;
  EXPECT_TRUE(find_isolated_outliers(coarse).empty());
}

// The output of a first-order process whose input a test engineer steps at sample instants
// (thesis section 4-2): a kink at every step, exactly at a sample, sharp against little noise.
std::vector<double> stepped_response(std::size_t n, std::size_t hold, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> level(-1.0, 1.0);
  std::normal_distribution<double> normal(0.0, sigma);
  const double decay = std::exp(-0.75 / 3.0);  // step 0.75 min, time constant 3 min
  std::vector<double> y(n);
  double state = 0, input = level(rng);
  for (std::size_t i = 0; i < n; ++i) {
    if (i % hold == 0) input = level(rng);
    y[i] = state + (sigma > 0 ? normal(rng) : 0.0);
    state = input + (state - input) * decay;  // exact over one sample of held input
  }
  return y;
}

TEST(IsolatedOutliers, KinksOfAStepResponseAreNotOutliers) {
  for (const std::size_t hold : {1, 2, 5, 20})
    for (const double sigma : {0.0, 1e-4, 1e-3, 1e-2})
      for (unsigned seed = 1; seed <= 3; ++seed) {
        EXPECT_TRUE(find_isolated_outliers(stepped_response(115, hold, sigma, seed)).empty()) << "hold " << hold << ", noise " << sigma;
        EXPECT_TRUE(find_isolated_outliers(stepped_response(3000, hold, sigma, seed)).empty()) << "hold " << hold << ", noise " << sigma;
      }
  // A glitch in it is still found: of 50 noise levels, midway between two steps of the input
  // (20 samples apart: the scale is that of the signal's own roughness, and a step every 5 samples
  // hides it); two samples after a step, the kink is in its stencil, and it is left alone.
  auto y = stepped_response(3000, 20, 1e-3, 9);
  y[1510] += 0.05;
  EXPECT_EQ(samples_of(find_isolated_outliers(y)), std::vector<std::size_t>{1510});
  y[1510] -= 0.05;
  y[1502] += 0.05;
  EXPECT_TRUE(find_isolated_outliers(y).empty());
}

TEST(IsolatedOutliers, ConstantShortAndNonFiniteSignalsHaveNone) {
  EXPECT_TRUE(find_isolated_outliers(std::vector<double>(100, 2.5)).empty());
  auto short_one = with_noise(sampled(kMinOutlierSamples - 1, 0.1, oscillation), 1e-3, 1);
  short_one[9] += 10;
  EXPECT_TRUE(find_isolated_outliers(short_one).empty());
  auto with_nan = with_noise(sampled(500, 0.1, oscillation), 1e-3, 1);
  with_nan[100] = 10;
  with_nan[300] = std::nan("");
  EXPECT_TRUE(find_isolated_outliers(with_nan).empty());
}

TEST(IsolatedOutliers, ALongRecordIsScannedWhole) {
  // Beyond 200,000 samples the scale comes from evenly spaced stretches; every sample is examined.
  const std::size_t n = 1'000'000;
  auto y = with_noise(sampled(n, 0.001, oscillation), 1e-3, 11);
  const std::vector<std::size_t> glitches{10, 123457, 500001, 999980};
  for (const std::size_t i : glitches) y[i] -= 0.05;
  EXPECT_EQ(samples_of(find_isolated_outliers(y)), glitches);
}

}  // namespace sidc::outliers_test
