// The difference-based noise estimate (see noise_level.hpp).
#include "runtime/operators/noise_level.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "runtime/robust_scale.hpp"

namespace sidc {
namespace {

double binomial(int n, int k) {
  double c = 1;
  for (int i = 1; i <= k; ++i) c = c * (n - k + i) / i;
  return c;
}

// The pieces of the signal the estimate reads: the whole signal, or kChunks evenly spaced
// contiguous chunks when it is longer than kMaxNoiseSamples.
std::vector<std::span<const double>> pieces_of(std::span<const double> y) {
  if (y.size() <= kMaxNoiseSamples) return {y};
  constexpr std::size_t kChunks = 20;
  const std::size_t length = kMaxNoiseSamples / kChunks;
  std::vector<std::span<const double>> out;
  for (std::size_t c = 0; c < kChunks; ++c) {
    const std::size_t start = (y.size() - length) * c / (kChunks - 1);
    out.push_back(y.subspan(start, length));
  }
  return out;
}

}  // namespace

double standard_deviation(std::span<const double> y) {
  if (y.empty()) return 0;
  double mean = 0;
  for (double v : y) mean += v;
  mean /= static_cast<double>(y.size());
  double largest = 0;
  for (double v : y) largest = std::max(largest, std::abs(v - mean));
  double ss = 0;
  if (largest > 0)
    for (double v : y) ss += ((v - mean) / largest) * ((v - mean) / largest);
  return largest * std::sqrt(ss / static_cast<double>(y.size()));
}

NoiseLevel estimate_noise_level(std::span<const double> y) {
  NoiseLevel level;
  level.samples = y.size();
  if (y.empty()) return level;
  level.spread = standard_deviation(y);
  level.constant = std::all_of(y.begin(), y.end(), [&](double v) { return v == y.front(); });
  if (level.constant || y.size() < 3) return level;

  const auto pieces = pieces_of(y);
  std::vector<std::vector<double>> differences;  // per piece, of the current order
  for (const auto& p : pieces) differences.emplace_back(p.begin(), p.end());
  double previous = -1;
  for (int k = 1; k <= kMaxDifferenceOrder; ++k) {
    std::vector<double> all;
    for (auto& d : differences) {
      for (std::size_t i = 0; i + 1 < d.size(); ++i) d[i] = d[i + 1] - d[i];
      if (!d.empty()) d.pop_back();
      all.insert(all.end(), d.begin(), d.end());
    }
    if (all.size() < 2) break;  // too short for this order: keep the last estimate
    const double estimate = robust_scale(std::move(all)) / std::sqrt(binomial(2 * k, k));
    if (previous >= 0 && estimate >= 0.95 * previous) break;  // stopped falling: noise only
    level.sigma = estimate;
    level.difference_order = k;
    previous = estimate;
    if (estimate == 0) break;  // exactly a polynomial of degree < k
  }
  return level;
}

}  // namespace sidc
