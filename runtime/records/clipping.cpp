#include "runtime/records/clipping.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ir/queries.hpp"
#include "runtime/robust_scale.hpp"

namespace sidc {
namespace {

constexpr std::size_t kMinSamples = 20;
constexpr std::size_t kMinClipped = 3;        // test 1
constexpr std::size_t kMinLongestRun = 3;     // ... and one run at least this long (a peak sampled
                                              // symmetrically, and rounded, repeats its top twice)
constexpr double kMaxOrdinaryRepeats = 0.01;  // test 2
constexpr double kArrivalShare = 0.1;         // test 3: a tenth of the median step (a sine clipped at
                                              // 95% of its amplitude arrives at a third of it)
constexpr std::size_t kMaxMedianSamples = 200000;

// Test 1 and the runs' fastest way in or out, for the rail `value`.
struct Runs {
  ClippedSide side;
  double fastest_entry = 0;
  std::size_t longest = 0;
};

Runs runs_at(std::span<const double> y, double value) {
  Runs out;
  out.side.value = value;
  const std::size_t n = y.size();
  for (std::size_t i = 0; i < n;) {
    if (y[i] != value) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < n && y[j] == value) ++j;
    if (j - i >= 2) {
      if (out.side.runs == 0) out.side.first = i;
      out.side.last = j - 1;
      ++out.side.runs;
      out.side.samples += j - i;
      out.longest = std::max(out.longest, j - i);
      if (i > 0) out.fastest_entry = std::max(out.fastest_entry, std::abs(y[i] - y[i - 1]));
      if (j < n) out.fastest_entry = std::max(out.fastest_entry, std::abs(y[j] - y[j - 1]));
    }
    i = j;
  }
  return out;
}

// The median absolute difference of neighbours (evenly spaced stretches beyond kMaxMedianSamples;
// pairs with a faulty sample skipped).
double median_difference(std::span<const double> y) {
  const std::size_t count = y.size() - 1, stride = std::max<std::size_t>(1, count / kMaxMedianSamples);
  std::vector<double> d;
  d.reserve(count / stride + 1);
  for (std::size_t i = 1; i < y.size(); i += stride)
    if (const double step = std::abs(y[i] - y[i - 1]); std::isfinite(step)) d.push_back(step);
  return d.empty() ? 0.0 : median_in_place(d);
}

}  // namespace

Clipping find_clipping(std::span<const double> y) {
  Clipping out;
  const std::size_t n = y.size();
  // The rails among the finite samples (a faulty cell is no sample, and breaks a run).
  double low = std::numeric_limits<double>::infinity(), high = -low;
  std::size_t finite = 0;
  for (const double v : y)
    if (std::isfinite(v)) {
      low = std::min(low, v);
      high = std::max(high, v);
      ++finite;
    }
  if (finite < kMinSamples || low == high) return out;  // too short, or constant: nothing is clipped, or everything
  Runs top = runs_at(y, high), bottom = runs_at(y, low);
  if (top.side.samples < kMinClipped && bottom.side.samples < kMinClipped) return out;
  // Test 2: repeats of neighbours away from the rails.
  std::size_t repeats = 0, pairs = 0;
  for (std::size_t i = 1; i < n; ++i) {
    if (!std::isfinite(y[i]) || !std::isfinite(y[i - 1]) || y[i] == high || y[i] == low || y[i - 1] == high || y[i - 1] == low) continue;
    ++pairs;
    repeats += y[i] == y[i - 1];
  }
  if (pairs == 0 || static_cast<double>(repeats) >= kMaxOrdinaryRepeats * static_cast<double>(pairs)) return out;
  // Test 3.
  const double typical = median_difference(y);
  for (Runs* r : {&top, &bottom})
    r->side.found = r->side.samples >= kMinClipped && r->longest >= kMinLongestRun && r->fastest_entry > kArrivalShare * typical;
  out.top = top.side;
  out.bottom = bottom.side;
  return out;
}

std::vector<char> clipped_samples(std::span<const double> y) {
  const Clipping c = find_clipping(y);
  std::vector<char> out;
  if (!c.found()) return out;
  out.assign(y.size(), 0);
  for (const ClippedSide* side : {&c.top, &c.bottom}) {
    if (!side->found) continue;
    for (std::size_t i = 0; i < y.size(); ++i)
      if (y[i] == side->value && ((i > 0 && y[i - 1] == side->value) || (i + 1 < y.size() && y[i + 1] == side->value))) out[i] = 1;
  }
  return out;
}

std::vector<Clipping> clipped_outputs(const SampledRecord& record, const ir::Model& model) {
  std::vector<Clipping> out;
  if (is_static(model)) return out;
  for (const ir::Signal& s : model.signals) {
    if (s.kind != ir::Signal::Kind::output) continue;
    const auto it = record.signals.find(s.name);
    if (it == record.signals.end()) continue;
    Clipping c = find_clipping(it->second);
    if (!c.found()) continue;
    c.record = record.path;
    c.signal = s.name;
    c.step = record.step;
    std::size_t first = record.time.size(), last = 0;
    for (const ClippedSide* side : {&c.top, &c.bottom})
      if (side->found) {
        first = std::min(first, side->first);
        last = std::max(last, side->last);
      }
    c.first_time = record.time[first];
    c.last_time = record.time[last];
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace sidc
