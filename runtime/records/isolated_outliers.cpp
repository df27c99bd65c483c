#include "runtime/records/isolated_outliers.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <boost/math/distributions/normal.hpp>

#include "ir/queries.hpp"
#include "runtime/robust_scale.hpp"

namespace sidc {
namespace {

constexpr std::size_t kHalf = 3;                 // samples either side in the stencil
constexpr std::size_t kSide = 4;                 // samples each side's line is fitted to
constexpr std::size_t kLocal = 64;               // samples either side of the stencil in the local scale
constexpr std::size_t kMaxScaleSamples = 200000;  // residuals the global scale is read from
constexpr std::size_t kStretch = 1000;            // ... in evenly spaced stretches of this many
constexpr double kFamilyFalseAlarm = 0.01;        // chance of one false alarm on a whole Gaussian signal
// Test 3's bound on each side's miss, in units of the one-sided residuals' robust scale: noise
// alone exceeds it with about 0.3% chance.
constexpr double kSideBound = 3.0;

// The imprint of a unit spike at i on the residual at distance d = 1, 2, 3: minus its weight in
// the neighbour's prediction (the pair mean halves 6/7, 3/7, -2/7).
constexpr double kImprint[kHalf + 1] = {1.0, -3.0 / 7, -3.0 / 14, 1.0 / 7};

double predicted(std::span<const double> y, std::size_t i) {
  return 6.0 / 7 * 0.5 * (y[i - 1] + y[i + 1]) + 3.0 / 7 * 0.5 * (y[i - 2] + y[i + 2]) - 2.0 / 7 * 0.5 * (y[i - 3] + y[i + 3]);
}

// The centred residual of test 1, and the one-sided residual of test 3: y_i off the straight line
// fitted by least squares to the four samples before it, continued to t_i (weights 1, 1/2, 0,
// -1/2 on y_{i-1}, ..., y_{i-4}; 2.5 times the noise variance of y).
double residual(std::span<const double> y, std::size_t i) { return y[i] - predicted(y, i); }
double from_left(std::span<const double> y, std::size_t i) { return y[i] - (y[i - 1] + 0.5 * y[i - 2] - 0.5 * y[i - 4]); }
double from_right(std::span<const double> y, std::size_t i) { return y[i] - (y[i + 1] + 0.5 * y[i + 2] - 0.5 * y[i + 4]); }
using Residual = double (*)(std::span<const double>, std::size_t);

// The residuals' robust scale over the whole signal (evenly spaced stretches beyond kMaxScaleSamples).
double global_scale(std::span<const double> y, Residual f) {
  const std::size_t first = kSide, last = y.size() - kSide;  // residuals at [first, last)
  const std::size_t count = last - first;
  std::vector<double> r;
  if (count <= kMaxScaleSamples) {
    r.reserve(count);
    for (std::size_t i = first; i < last; ++i) r.push_back(f(y, i));
  } else {
    const std::size_t stretches = kMaxScaleSamples / kStretch;
    r.reserve(stretches * kStretch);
    for (std::size_t s = 0; s < stretches; ++s) {
      const std::size_t start = first + s * (count - kStretch) / (stretches - 1);
      for (std::size_t i = start; i < start + kStretch; ++i) r.push_back(f(y, i));
    }
  }
  return robust_scale(std::move(r));
}

// The quantisation step q of the signal: the smallest non-zero difference of neighbours (0 when
// all are equal). Uniform rounding error has variance q^2 / 12.
double quantisation_step(std::span<const double> y) {
  double q = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < y.size(); ++i)
    if (const double d = std::abs(y[i] - y[i - 1]); d > 0 && d < q) q = d;
  return std::isfinite(q) ? q : 0.0;
}

// The same MAD over the kLocal samples either side of i's stencil.
double local_scale(std::span<const double> y, std::size_t i, Residual f) {
  std::vector<double> r;
  r.reserve(2 * kLocal);
  const std::size_t lo = std::max(kSide, i >= kHalf + 1 + kLocal ? i - kHalf - kLocal : kSide);
  const std::size_t hi = std::min(y.size() - kSide, i + kHalf + 1 + kLocal);
  for (std::size_t k = lo; k + kHalf < i; ++k) r.push_back(f(y, k));
  for (std::size_t k = i + kHalf + 1; k < hi; ++k) r.push_back(f(y, k));
  return r.size() >= 8 ? robust_scale(std::move(r)) : 0.0;
}

// Test 2: the six neighbours' residuals, the spike's imprint taken out, all within the bound.
bool alone(std::span<const double> y, std::size_t i, double spike, double bound) {
  for (std::size_t d = 1; d <= kHalf; ++d)
    for (const std::size_t k : {i - d, i + d})
      if (k >= kHalf && k + kHalf < y.size() && std::abs(residual(y, k) - kImprint[d] * spike) > bound) return false;
  return true;
}

// Test 3: each side's straight line continued to t_i nearer the neighbours' quadratic than y_i
// (a spike leaves the signal, and all three predictions, where they were), and off y_i by more
// than kSideBound of the one-sided residuals' robust scale (where kinks are only a few samples
// apart, as in the response to a fast binary input, no line continues a smooth stretch: that
// scale is then large), both the way of r. A kink between samples, or at one, leaves y_i on one
// side's line.
bool off_both_sides(std::span<const double> y, std::size_t i, double spike, double side_scale) {
  const double left = from_left(y, i), right = from_right(y, i);
  const double bound = std::max(0.5 * std::abs(spike), kSideBound * side_scale);
  return left * spike > 0 && right * spike > 0 && std::abs(left) > bound && std::abs(right) > bound;
}

}  // namespace

std::vector<IsolatedOutlier> find_isolated_outliers(std::span<const double> y, std::span<const double> time, double* threshold) {
  std::vector<IsolatedOutlier> found;
  if (threshold) *threshold = 0;
  const std::size_t n = y.size();
  if (n < kMinOutlierSamples || !std::all_of(y.begin(), y.end(), [](double v) { return std::isfinite(v); })) return found;
  const double z = boost::math::quantile(boost::math::normal(), 1 - kFamilyFalseAlarm / 2 / static_cast<double>(n - 2 * kSide));
  if (threshold) *threshold = z;
  const double q = quantisation_step(y);
  // Rounding to q through the centred stencil (variance factor 1.5) and a side's line (2.5).
  const double scale = std::max(global_scale(y, residual), std::sqrt(1.5 / 12) * q);
  const double side_scale = std::max(global_scale(y, from_left), std::sqrt(2.5 / 12) * q);
  if (!(scale > 0)) return found;  // constant, or exactly a cubic
  for (std::size_t i = kSide; i + kSide < n; ++i) {
    const double r = residual(y, i);
    if (!(std::abs(r) > z * scale) || !alone(y, i, r, z * scale) || !off_both_sides(y, i, r, side_scale)) continue;
    const double here = std::max(scale, local_scale(y, i, residual));
    if (!(std::abs(r) > z * here) || !alone(y, i, r, z * here) || !off_both_sides(y, i, r, std::max(side_scale, local_scale(y, i, from_left))))
      continue;
    found.push_back({i, time.empty() ? 0.0 : time[i], y[i], predicted(y, i), std::abs(r) / here});
  }
  return found;
}

std::vector<OutlierScan> replace_isolated_outliers(SampledRecord& record, const ir::Model& model) {
  std::vector<OutlierScan> scans;
  if (is_static(model)) return scans;
  for (const ir::Signal& s : model.signals) {
    if (s.kind != ir::Signal::Kind::output) continue;
    const auto it = record.signals.find(s.name);
    if (it == record.signals.end()) continue;
    OutlierScan scan;
    scan.record = record.path;
    scan.step = record.step;
    scan.signal = s.name;
    const auto column = record.columns.find(s.name);
    scan.column = column == record.columns.end() ? s.name : column->second;
    scan.found = find_isolated_outliers(it->second, record.time, &scan.threshold);
    if (scan.found.empty()) continue;
    // No two are within three samples (each would be in the other's stencil, and neither alone),
    // so no replacement changes another's prediction.
    std::vector<double>& y = it->second.owned();
    for (const IsolatedOutlier& o : scan.found) y[o.sample] = o.replacement;
    scans.push_back(std::move(scan));
  }
  return scans;
}

}  // namespace sidc
