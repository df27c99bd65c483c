// A clipped output (runtime/records/clipping.hpp): a sine through a sensor that saturates is found
// on the side it saturates, with the rail, its runs and samples; an unclipped sine, a response that
// settles exactly, a coarsely quantised signal and a short one are not.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "runtime/records/clipping.hpp"

namespace sidc::clipping_test {

std::vector<double> sine(std::size_t n, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, noise);
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i) y[i] = std::sin(0.05 * static_cast<double>(i)) + 0.3 * std::sin(0.13 * static_cast<double>(i)) + (noise > 0 ? normal(rng) : 0.0);
  return y;
}

std::vector<double> clipped(std::vector<double> y, double low, double high) {
  for (double& v : y) v = std::clamp(v, low, high);
  return y;
}

TEST(Clipping, ASaturatedSensorIsFoundOnTheSideItSaturates) {
  for (const double noise : {0.0, 1e-3, 1e-2}) {
    const auto y = clipped(sine(4000, noise, 3), -10.0, 0.9);
    const Clipping c = find_clipping(y);
    EXPECT_TRUE(c.top.found) << "noise " << noise;
    EXPECT_FALSE(c.bottom.found) << "noise " << noise;
    EXPECT_EQ(c.top.value, 0.9);
    EXPECT_EQ(c.top.samples, static_cast<std::size_t>(std::count(y.begin(), y.end(), 0.9)));
    EXPECT_GE(c.top.runs, 5u);
    EXPECT_EQ(y[c.top.first], 0.9);
    EXPECT_EQ(y[c.top.last], 0.9);
  }
  const Clipping both = find_clipping(clipped(sine(4000, 1e-3, 4), -0.9, 0.9));
  EXPECT_TRUE(both.top.found);
  EXPECT_TRUE(both.bottom.found);
  EXPECT_EQ(both.bottom.value, -0.9);
}

TEST(Clipping, UnclippedSignalsAreNot) {
  for (const double noise : {0.0, 1e-3, 1e-2}) EXPECT_FALSE(find_clipping(sine(4000, noise, 5)).found()) << "noise " << noise;
  // A step response written with 12 digits settles to exactly 1 and stays there: arrived at slowly.
  std::vector<double> settle(3000);
  for (std::size_t i = 0; i < settle.size(); ++i) {
    const double t = 0.05 * static_cast<double>(i % 1000);
    settle[i] = std::round((1 - std::exp(-t)) * 1e12) / 1e12;
  }
  EXPECT_FALSE(find_clipping(settle).found());
  // A slow sine through a coarse converter repeats values everywhere, its peaks too.
  auto coarse = sine(3000, 0.0, 1);
  for (double& v : coarse) v = std::round(v / 0.05) * 0.05;
  EXPECT_FALSE(find_clipping(coarse).found());
  // Too short, constant: nothing to say.
  EXPECT_FALSE(find_clipping(clipped(sine(19, 0.0, 1), -1, 0.1)).found());
  EXPECT_FALSE(find_clipping(std::vector<double>(100, 1.0)).found());
}

TEST(Clipping, AFaultyCellIsNoSampleAndTheClippedSamplesAreMarked) {
  auto y = clipped(sine(1000, 1e-3, 1), -10.0, 0.9);
  y[10] = std::nan("");
  const Clipping c = find_clipping(y);
  ASSERT_TRUE(c.top.found);
  const auto marked = clipped_samples(y);
  ASSERT_EQ(marked.size(), y.size());
  std::size_t count = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    count += marked[i] != 0;
    if (marked[i]) {
      EXPECT_EQ(y[i], 0.9);
    }
  }
  EXPECT_EQ(count, c.top.samples);
  EXPECT_TRUE(clipped_samples(sine(1000, 1e-3, 1)).empty());
}

}  // namespace sidc::clipping_test
