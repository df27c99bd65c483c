// Isolated outliers of a recorded output: single samples a sensor glitch, a dropped bit or a
// spike of interference put far off the curve their neighbours follow. One such sample in 4,000
// moves a least-squares fit of a dynamic model by far more than the record's noise does (its
// moving-arc derivatives spread it over a dozen rows; a forced Duffing record with three glitches
// of ten times its s.d. gave k3 = -0.008 for 0.5), and the validation then compares the solved
// equations with the glitch. The output of a continuous-time system cannot jump between two samples and
// back, so such a sample is an error of the record, not of the model: it is found, reported and
// replaced by the value its neighbours give, before any operation is evaluated.
//
// Method. r_i = y_i - p_i, where p_i is the value at t_i of the least-squares quadratic through
// the three samples either side of i (not i itself): p_i = 6/7 m_1 + 3/7 m_2 - 2/7 m_3, with m_j
// the mean of y_{i-j} and y_{i+j} (exact for cubics; r_i has 1.5 times the noise variance of y).
// Sample i is an isolated outlier when
//   1. |r_i| exceeds z times the residuals' scale: 1.4826 times the median absolute deviation of
//      r over the signal (robust to the outliers themselves), not less than the residual a
//      quantisation step q of the signal gives (sqrt(1.5/12) q), nor than the same MAD over the
//      64 samples either side beyond the stencil (a record whose variation grows along it);
//      z is Bonferroni's bound over the n - 6 residuals for a 1% chance, under Gaussian noise, of
//      one false alarm on the whole signal: z = Phi^-1(1 - 0.005 / (n - 6)) (4.7 at n = 4,000,
//      6.1 at 10^7); and
//   2. it is alone: a spike of height A at i gives its neighbours the residuals -3/7 A, -3/14 A and
//      1/7 A (at distance 1, 2, 3); with that imprint taken out, none of the six exceeds z times
//      the scale (a step or a burst of bad samples fails this test); and
//   3. it is off both sides: the straight lines fitted by least squares to the four samples
//      before i and to the four after, continued to t_i, both miss y_i on the side of r_i, each by
//      more than |r_i| / 2 (they lie nearer p_i: a spike leaves the signal where it was) and by
//      more than 3 times the robust scale of such one-sided residuals (over the signal, by
//      quantisation and locally, as in test 1; large where kinks are only a few samples apart).
//      A kink between samples, or at one, leaves y_i on one side's line however sharp it is:
//      the output of a system whose input steps (thesis section 4-2) has them.
//   With Gaussian noise of s.d. sigma on 4,000 samples, a glitch of 7 sigma is found in about half
//   the cases, one of 10 sigma in 97%, one of 12 sigma always; next to a glitch of 5 to 8 sigma its
//   neighbour is now and then taken instead.
// The first and last four samples (no line on both sides) are not examined, and a glitch within
// four samples of a kink is left alone (the kink spoils its neighbours' curve).
//
// Relies on: Boost.Math's normal quantile. Guarantees: no exceptions; a signal shorter than
// kMinOutlierSamples, constant, or exactly a cubic, has none; cost O(n) and O(1) extra memory for
// a clean signal (the scale from at most 200,000 residuals in evenly spaced stretches); a
// borrowed column is copied only when something is replaced (tests/runtime/isolated_outliers_test.cpp).
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "ir/ir.hpp"
#include "runtime/records/sampled_record.hpp"

namespace sidc {

inline constexpr std::size_t kMinOutlierSamples = 20;

struct IsolatedOutlier {
  std::size_t sample = 0;   // index in the record's grid
  double time = 0;          // the record's time there
  double value = 0;         // as recorded
  double replacement = 0;   // the neighbours' quadratic at t_i
  double size = 0;          // |r_i| in units of the residuals' scale there
};

struct OutlierScan {
  std::string record;       // its path, for messages
  std::string signal;
  std::string column;       // the record column it came from
  double threshold = 0;     // z
  double step = 0;          // the record's sampling step (times printed with the digits it needs)
  std::vector<IsolatedOutlier> found;
};

// The isolated outliers of `y` (uniformly sampled), in order of their sample; `threshold` (optional)
// receives z. `time` (optional, same length) gives each its time.
std::vector<IsolatedOutlier> find_isolated_outliers(std::span<const double> y, std::span<const double> time = {},
                                                    double* threshold = nullptr);

// Every recorded output of a dynamic `model` in `record` scanned, and its isolated outliers replaced
// in place; one scan per output that had any. A static model's rows are no time series: nothing.
std::vector<OutlierScan> replace_isolated_outliers(SampledRecord& record, const ir::Model& model);

}  // namespace sidc
