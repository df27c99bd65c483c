// The median and the robust scale of a sample, 1.4826 * MAD (the median absolute deviation from the
// median, consistent for a normal law and blind to a few wild values): what the noise level of a
// signal (operators/noise_level.cpp) and the scans of a record for glitches and clipping
// (records/isolated_outliers.cpp, records/clipping.cpp) read a scale from. One name for every file
// of runtime/.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace sidc {

// 1 / Phi^-1(3/4): the MAD of a normal law times this is its standard deviation.
inline constexpr double kMadToSigma = 1.482602218505602;

// The median of `v` (the mean of the two middle values for an even count), reordering `v`.
inline double median_in_place(std::vector<double>& v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  double m = *mid;
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), mid));
  return m;
}

// 1.4826 * median |x - median(x)|; 0 for no values.
inline double robust_scale(std::vector<double> x) {
  if (x.empty()) return 0;
  const double centre = median_in_place(x);
  for (double& v : x) v = std::abs(v - centre);
  return kMadToSigma * median_in_place(x);
}

}  // namespace sidc
