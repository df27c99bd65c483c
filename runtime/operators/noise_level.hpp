// The noise level of a sampled signal, estimated from the signal alone: the scale of the
// measurement error the derivative operators must smooth against (issue 13; the thesis' warning
// that differentiation is "the most difficult and uncertain" of the operations, section 3-1).
//
// Method: differences of order k of white noise e of standard deviation sigma have variance
// sigma^2 * C(2k, k) (the squared binomial coefficients sum to C(2k, k)); the smooth part s of the
// signal contributes at most about (h * bandwidth)^k times its amplitude, which shrinks with k
// when the record is sampled finer than its variation. So for k = 1, 2, ..., kMaxDifferenceOrder
// the robust scale of the k-th differences, 1.4826 * MAD (the median absolute deviation from
// their median, consistent for a normal law and blind to a few large differences at kinks or
// outliers), divided by sqrt(C(2k, k)), estimates sigma plus a smooth-part share that drops with
// k until only the noise is left. The order used is the first k after which the estimate stops
// falling (the next is at least 95% of it); a signal sampled too coarsely for that gets the
// last order's estimate, an upper bound. This is the difference-based variance estimator of
// Rice (1984) and Hall, Kay and Titterington (1990), with the order chosen from the data, and
// with the MAD in place of the mean square as Donoho (1995) does for wavelet details.
//
// Relies on: <cmath>, <algorithm> only. Guarantees: no exceptions; a constant signal has sigma 0
// and `constant` set; a signal whose k-th differences are exactly 0 (a polynomial of degree < k
// written exactly) has sigma 0. Records longer than kMaxNoiseSamples are read in evenly spaced
// contiguous chunks, so the cost stays bounded (tests/runtime/noise_level_test.cpp).
#pragma once

#include <cstddef>
#include <span>

namespace sidc {

inline constexpr int kMaxDifferenceOrder = 8;
inline constexpr std::size_t kMaxNoiseSamples = 200000;

struct NoiseLevel {
  double sigma = 0;          // estimated standard deviation of the noise, in the signal's units
  double spread = 0;         // standard deviation of the samples themselves
  int difference_order = 0;  // k of the differences the estimate came from (0: constant or too short)
  std::size_t samples = 0;
  bool constant = false;     // every sample equal

  // sigma / spread: 0.01 for noise of 1% of the signal's standard deviation; 0 for a constant signal.
  double relative() const { return spread > 0 ? sigma / spread : 0.0; }
  // The noise's variance is larger than that of what is left of the signal (spread^2 - sigma^2):
  // derivatives of such a signal are mostly noise, whatever the operator.
  bool exceeds_variation() const { return spread > 0 && 2 * sigma * sigma > spread * spread; }
};

// The noise level of `samples` (uniformly spaced; the spacing does not enter). Fewer than 3
// samples: sigma 0, difference_order 0.
NoiseLevel estimate_noise_level(std::span<const double> samples);

// The standard deviation of the samples (divided by n), with squares taken relative to the
// largest deviation: finite and non-zero for a record in units of 1e200 or 1e-200 alike.
double standard_deviation(std::span<const double> samples);

}  // namespace sidc
