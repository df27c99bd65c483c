// Residual autocorrelation and residual-input cross-correlation; see residual_correlation.hpp for
// the estimator, the band and the verdict rule.
#include "runtime/solve/residual_correlation.hpp"

#include <algorithm>
#include <cmath>

#include <boost/math/distributions/normal.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "runtime/parallel_ranges.hpp"

namespace sidc {
namespace {

// Two-sided normal quantile: z with P(|Z| > z) = alpha.
double two_sided_z(double alpha) {
  const boost::math::normal standard;
  return boost::math::quantile(boost::math::complement(standard, alpha / 2));
}

// The largest count of lags outside the band that white residuals exceed with probability at
// most alpha: smallest k with P(X > k) <= alpha, X ~ Binomial(lags, p).
int binomial_allowance(int lags, double p, double alpha) {
  double cumulative = 0;
  double term = std::pow(1 - p, lags);  // P(X = 0)
  for (int k = 0; k <= lags; ++k) {
    cumulative += term;
    if (1 - cumulative <= alpha) return k;
    term *= static_cast<double>(lags - k) / static_cast<double>(k + 1) * p / (1 - p);
  }
  return lags;
}

// Sorted lags as a short list: runs of three or more consecutive lags as "a to b" ("1 to 25"),
// at most eight items, then "and N more lags".
std::string lag_list(const std::vector<int>& lags) {
  std::vector<std::string> items;
  std::size_t i = 0, listed = 0;
  while (i < lags.size() && items.size() < 8) {
    std::size_t j = i;
    while (j + 1 < lags.size() && lags[j + 1] == lags[j] + 1) ++j;
    if (j - i >= 2) {
      items.push_back(fmt::format("{} to {}", lags[i], lags[j]));
      listed += j - i + 1;
      i = j + 1;
    } else {
      items.push_back(std::to_string(lags[i]));
      ++listed;
      ++i;
    }
  }
  std::string text = fmt::format("{}", fmt::join(items, ", "));
  if (listed < lags.size()) text += fmt::format(" and {} more lags", lags.size() - listed);
  return text;
}

// Mean-removed copies of the segments that are long enough.
std::vector<std::vector<double>> centred(const std::vector<std::vector<double>>& segments,
                                         const std::vector<bool>& used) {
  std::vector<std::vector<double>> out;
  for (std::size_t s = 0; s < segments.size(); ++s) {
    if (!used[s]) continue;
    const auto& segment = segments[s];
    long double sum = 0;
    for (double v : segment) sum += v;
    const double mean = static_cast<double>(sum / static_cast<long double>(segment.size()));
    std::vector<double> c(segment.size());
    for (std::size_t t = 0; t < segment.size(); ++t) c[t] = segment[t] - mean;
    out.push_back(std::move(c));
  }
  return out;
}

// sum_s sum_t a_s(t+k) b_s(t), within each segment only; k may be negative.
long double lagged_sum(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b, int k) {
  long double sum = 0;
  for (std::size_t s = 0; s < a.size(); ++s) {
    const auto length = static_cast<long>(a[s].size());
    const long first = std::max<long>(0, -k), last = std::min<long>(length, length - k);  // t in [first, last)
    for (long t = first; t < last; ++t) sum += static_cast<long double>(a[s][t + k]) * b[s][t];
  }
  return sum;
}

// lagged_sum(a, b, k) for k = first, ..., last, the lags shared among the cores: each sum is made
// exactly as one thread makes it, so the values do not depend on the number of cores.
std::vector<long double> lagged_sums(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b, int first, int last) {
  std::vector<long double> out(static_cast<std::size_t>(last - first + 1));
  std::size_t n = 0;
  for (const auto& segment : a) n += segment.size();
  for_parallel_ranges(out.size(), n * out.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) out[i] = lagged_sum(a, b, first + static_cast<int>(i));
  });
  return out;
}

// skip_zero: an autocorrelation (lag 0 is 1 by construction); its clean verdict is "looks white",
// a cross-correlation's "looks uncorrelated".
void judge(CorrelationCurve& curve, double band, double bonferroni_band, int allowance, bool skip_zero) {
  const char* clean = skip_zero ? "looks white" : "looks uncorrelated";
  bool beyond_bonferroni = false;
  for (std::size_t i = 0; i < curve.lags.size(); ++i) {
    if (skip_zero && curve.lags[i] == 0) continue;
    const double magnitude = std::fabs(curve.values[i]);
    if (magnitude > band) curve.lags_outside.push_back(curve.lags[i]);
    if (magnitude > bonferroni_band) beyond_bonferroni = true;
  }
  curve.white = !beyond_bonferroni && static_cast<int>(curve.lags_outside.size()) <= allowance;
  if (curve.white) {
    curve.verdict = curve.lags_outside.empty()
                        ? fmt::format("{} (no lag outside the band)", clean)
                        : fmt::format("{} ({} lag(s) outside the band, as chance allows: {})", clean,
                                      curve.lags_outside.size(), lag_list(curve.lags_outside));
  } else {
    curve.verdict = fmt::format("correlated at lags {}", lag_list(curve.lags_outside));
  }
}

}  // namespace

bool ResidualCorrelationOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string text) {
    if (why) *why = std::move(text);
    return false;
  };
  if (max_lag < 0) return fail(fmt::format("max_lag is {}; it must be 0 (automatic) or positive", max_lag));
  if (!(confidence_level > 0.5 && confidence_level < 1))
    return fail(fmt::format("confidence_level is {}; it must lie in (0.5, 1)", confidence_level));
  if (min_segment_length < 2) return fail("min_segment_length must be at least 2");
  return true;
}

const char* to_string(ResidualCorrelationSummary::Status status) {
  switch (status) {
    case ResidualCorrelationSummary::Status::success: return "success";
    case ResidualCorrelationSummary::Status::invalid_options: return "invalid options";
    case ResidualCorrelationSummary::Status::invalid_input: return "invalid input";
    case ResidualCorrelationSummary::Status::too_short: return "too short";
    case ResidualCorrelationSummary::Status::constant_residuals: return "constant residuals";
  }
  return "unknown";
}

std::vector<std::pair<std::size_t, std::size_t>> contiguous_segments(const std::vector<std::size_t>& key) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  std::size_t begin = 0;
  for (std::size_t i = 1; i <= key.size(); ++i) {
    if (i == key.size() || key[i] != key[begin]) {
      out.emplace_back(begin, i);
      begin = i;
    }
  }
  return out;
}

GroupResiduals group_residuals(const ir::Model& model, const std::vector<SampledRecord>& records, const FitOptions& options,
                               const FitSummary& summary, std::size_t group, const std::vector<std::string>& input_names,
                               std::size_t max_rows) {
  GroupResiduals out;
  for (const auto& name : input_names) out.inputs.push_back({name, {}});
  if (group >= summary.groups.size()) {
    out.message = fmt::format("there is no equation group {}", group + 1);
    return out;
  }
  std::size_t rows = 0, last_equation = SIZE_MAX, last_record = SIZE_MAX;
  const auto problem = for_each_residual_block(model, records, options, summary, group, [&](std::span<const ResidualRow> block) {
    for (const auto& r : block) {
      if (rows >= max_rows) {
        out.truncated = true;
        return false;
      }
      if (r.record >= records.size()) {
        out.message = fmt::format("a row names record {}, but {} were given", r.record + 1, records.size());
        return false;
      }
      const SampledRecord& record = records[r.record];
      // A new segment wherever the equation or the record changes: the join is no time step.
      if (r.equation != last_equation || r.record != last_record) {
        out.residuals.emplace_back();
        for (auto& in : out.inputs) in.segments.emplace_back();
        last_equation = r.equation, last_record = r.record;
      }
      const double position = record.step > 0 ? (r.time - record.time.front()) / record.step : 0;
      const auto sample = static_cast<std::size_t>(std::max(0.0, std::round(position)));
      if (sample >= record.time.size()) {
        out.message = fmt::format("a row at t = {} lies beyond record {}", r.time, record.path);
        return false;
      }
      const double weight = sample < record.weights.size() ? record.weights[sample] : 1.0;
      out.residuals.back().push_back(weight * r.residual);
      for (auto& in : out.inputs) {
        const auto found = record.signals.find(in.name);
        if (found == record.signals.end() || sample >= found->second.size()) {
          out.message = fmt::format("record {} has no signal `{}`", record.path, in.name);
          return false;
        }
        in.segments.back().push_back(found->second[sample]);
      }
      ++rows;
    }
    return true;
  }, max_rows == static_cast<std::size_t>(-1) ? max_rows : max_rows + 1);  // one more row tells `truncated`
  if (problem) out.message = problem->message;
  out.ok = out.message.empty();
  return out;
}

ResidualCorrelationSummary residual_correlation(const std::vector<std::vector<double>>& residual_segments,
                                                const std::vector<InputSegments>& inputs,
                                                const ResidualCorrelationOptions& options) {
  using Status = ResidualCorrelationSummary::Status;
  ResidualCorrelationSummary summary;
  summary.confidence_level = options.confidence_level;
  summary.autocorrelation.name = "residual autocorrelation";
  auto fail = [&](Status status, std::string message) {
    summary.status = status;
    summary.message = std::move(message);
    summary.verdict = "no residual analysis: " + summary.message;
    return summary;
  };

  std::string why;
  if (!options.is_valid(&why)) return fail(Status::invalid_options, why);

  for (std::size_t s = 0; s < residual_segments.size(); ++s)
    for (std::size_t t = 0; t < residual_segments[s].size(); ++t)
      if (!std::isfinite(residual_segments[s][t]))
        return fail(Status::invalid_input, fmt::format("residual {} of segment {} is not finite", t + 1, s + 1));
  for (const auto& input : inputs) {
    if (input.segments.size() != residual_segments.size())
      return fail(Status::invalid_input, fmt::format("input `{}` has {} segments, the residuals {}", input.name,
                                                     input.segments.size(), residual_segments.size()));
    for (std::size_t s = 0; s < input.segments.size(); ++s) {
      if (input.segments[s].size() != residual_segments[s].size())
        return fail(Status::invalid_input,
                    fmt::format("segment {} of input `{}` has {} samples, the residuals {}", s + 1, input.name,
                                input.segments[s].size(), residual_segments[s].size()));
      for (std::size_t t = 0; t < input.segments[s].size(); ++t)
        if (!std::isfinite(input.segments[s][t]))
          return fail(Status::invalid_input,
                      fmt::format("sample {} of segment {} of input `{}` is not finite", t + 1, s + 1, input.name));
    }
  }

  std::vector<bool> used(residual_segments.size());
  std::size_t longest = 0;
  for (std::size_t s = 0; s < residual_segments.size(); ++s) {
    used[s] = residual_segments[s].size() >= options.min_segment_length;
    if (!used[s]) continue;
    summary.n += residual_segments[s].size();
    ++summary.segments;
    longest = std::max(longest, residual_segments[s].size());
  }
  // Eight samples give at least two lags (N/4); anything shorter says nothing about whiteness.
  if (summary.n < 8)
    return fail(Status::too_short, fmt::format("{} residual(s) in segments of at least {} samples; at least 8 are needed",
                                               summary.n, options.min_segment_length));

  int max_lag = options.max_lag;
  if (max_lag == 0) max_lag = static_cast<int>(std::min<std::size_t>(25, summary.n / 4));
  max_lag = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(max_lag), longest - 1));
  summary.max_lag = max_lag;

  const auto e = centred(residual_segments, used);
  const long double r0 = lagged_sum(e, e, 0);
  const double scale_e = static_cast<double>(std::sqrt(r0 / static_cast<long double>(summary.n)));
  // A residual spread below 1e-14 of the residuals' own size is rounding noise, not a signal.
  double largest = 0;
  for (const auto& segment : residual_segments)
    for (double v : segment) largest = std::max(largest, std::fabs(v));
  if (r0 == 0 || scale_e <= 1e-14 * largest)
    return fail(Status::constant_residuals,
                "the residuals are constant on every record (an exact fit): there is nothing to correlate");

  const double alpha = 1 - options.confidence_level;
  summary.z = two_sided_z(alpha);
  const double root_n = std::sqrt(static_cast<double>(summary.n));
  summary.band = summary.z / root_n;
  summary.bonferroni_band = two_sided_z(alpha / max_lag) / root_n;

  auto& ac = summary.autocorrelation;
  const std::vector<long double> auto_sums = lagged_sums(e, e, 0, max_lag);
  for (int k = 0; k <= max_lag; ++k) {
    ac.lags.push_back(k);
    ac.values.push_back(static_cast<double>(auto_sums[static_cast<std::size_t>(k)] / r0));
  }
  ac.computed = true;
  judge(ac, summary.band, summary.bonferroni_band, binomial_allowance(max_lag, alpha, alpha), true);

  const int cross_lags = 2 * max_lag + 1;
  const double cross_bonferroni = two_sided_z(alpha / cross_lags) / root_n;
  const int cross_allowance = binomial_allowance(cross_lags, alpha, alpha);
  bool all_white = ac.white;
  std::vector<std::string> correlated_inputs;
  for (const auto& input : inputs) {
    CorrelationCurve curve;
    curve.name = input.name;
    const auto u = centred(input.segments, used);
    const long double u0 = lagged_sum(u, u, 0);
    double u_largest = 0;
    for (const auto& segment : input.segments)
      for (double v : segment) u_largest = std::max(u_largest, std::fabs(v));
    const double scale_u = static_cast<double>(std::sqrt(u0 / static_cast<long double>(summary.n)));
    if (u0 == 0 || scale_u <= 1e-14 * u_largest) {
      curve.verdict = "not computed: the input is constant on every record";
      summary.cross.push_back(std::move(curve));
      continue;
    }
    const long double norm = std::sqrt(r0 * u0);
    const std::vector<long double> cross_sums = lagged_sums(e, u, -max_lag, max_lag);
    for (int k = -max_lag; k <= max_lag; ++k) {
      curve.lags.push_back(k);
      curve.values.push_back(static_cast<double>(cross_sums[static_cast<std::size_t>(k + max_lag)] / norm));
    }
    curve.computed = true;
    judge(curve, summary.band, cross_bonferroni, cross_allowance, false);
    if (!curve.white) {
      all_white = false;
      correlated_inputs.push_back(input.name);
    }
    summary.cross.push_back(std::move(curve));
  }

  summary.status = Status::success;
  summary.residuals_white = all_white;
  if (all_white) {
    summary.verdict = "residuals look white";
    if (!inputs.empty()) summary.verdict += " and uncorrelated with the inputs";
  } else {
    std::vector<std::string> parts;
    if (!ac.white) parts.push_back(fmt::format("autocorrelated at lags {}", lag_list(ac.lags_outside)));
    for (const auto& curve : summary.cross)
      if (curve.computed && !curve.white)
        parts.push_back(fmt::format("correlated with `{}` at lags {}", curve.name, lag_list(curve.lags_outside)));
    summary.verdict = "residuals " + fmt::format("{}", fmt::join(parts, "; "));
  }
  return summary;
}

bool trust_newey_west(const ResidualCorrelationSummary& residuals, double hac_widening) {
  return residuals.is_usable() && (!residuals.autocorrelation.white || hac_widening > kHacWideningToTrust);
}

std::string ResidualCorrelationSummary::brief_report(double hac_widening) const {
  if (status != Status::success) return "residual analysis: " + message + "\n";
  std::string text = fmt::format(
      "residual analysis: {} residuals in {} segment(s), lags up to {}; correlations of mean-removed segments, "
      "divided by N (biased estimator); {:.0f}% band +-{:.4g}/sqrt(N) = +-{:.4g} under the whiteness hypothesis\n",
      n, segments, max_lag, confidence_level * 100, z, band);
  text += fmt::format("  autocorrelation: {}\n", autocorrelation.verdict);
  for (const auto& curve : cross) text += fmt::format("  cross-correlation with `{}`: {}\n", curve.name, curve.verdict);
  text += "  verdict: " + verdict + "\n";
  // What the whiteness verdict means for the fit's intervals (issue 15, item 4).
  if (!autocorrelation.white)
    text += "  for the intervals: the classical ones assume independent rows and are too narrow here; trust the Newey-West\n"
            "  (HAC) ones where the fit report gives them (docs/accuracy.md, \"Intervals under autocorrelated rows\")\n";
  else if (trust_newey_west(*this, hac_widening))
    text += fmt::format(
        "  for the intervals: the residuals look white, but the Newey-West (HAC) ones are up to {:.3g} times as wide as the\n"
        "  classical ones: the rows are correlated beyond what this test resolves at this length (an int() or a moving arc\n"
        "  of a noisy signal carries each sample's noise into many rows); trust the Newey-West ones (docs/accuracy.md)\n",
        hac_widening);
  else
    text += "  for the intervals: the classical ones assume independent rows, and the residuals do not contradict it\n";
  return text;
}

}  // namespace sidc
