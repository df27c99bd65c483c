// Test support for the tests of single sampled signals (tests/runtime: noise levels, isolated
// outliers): a function sampled on a uniform grid, and Gaussian noise added with a seeded engine.
#pragma once

#include <cstddef>
#include <functional>
#include <random>
#include <vector>

namespace sidc::testing {

// f(0), f(step), ..., f((n - 1) * step).
inline std::vector<double> sampled(std::size_t n, double step, const std::function<double(double)>& f) {
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i) y[i] = f(static_cast<double>(i) * step);
  return y;
}

// `y` with white Gaussian noise of s.d. `sigma` (std::mt19937 seeded with `seed`) added.
inline std::vector<double> with_noise(std::vector<double> y, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma);
  for (double& v : y) v += normal(rng);
  return y;
}

}  // namespace sidc::testing
