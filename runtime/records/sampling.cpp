#include "runtime/records/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sidc {
namespace {

// Widening of window bounds and of the resampling grid's end, in steps: absorbs the rounding of
// times such as 82 * 0.01 without ever taking in a whole extra sample.
constexpr double kTimeFuzzInSteps = 1e-6;

double typical_step(std::span<const double> time) {
  return time.size() >= 2 ? (time.back() - time.front()) / static_cast<double>(time.size() - 1) : 0.0;
}

}  // namespace

StepCheck check_uniform_step(std::span<const double> time, const UniformStepOptions& options) {
  StepCheck check;
  const std::size_t n = time.size();
  if (n < 2) {
    check.status = StepCheck::Status::too_few_samples;
    check.bad_index = n;
    return check;
  }
  double least = std::numeric_limits<double>::infinity(), most = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(time[i])) {
      check.status = StepCheck::Status::not_finite;
      check.bad_index = i;
      return check;
    }
    if (i == 0) continue;
    const double d = time[i] - time[i - 1];
    if (d <= 0) {
      check.status = d == 0 ? StepCheck::Status::repeats : StepCheck::Status::goes_backwards;
      check.bad_index = i;
      return check;
    }
    least = std::min(least, d);
    most = std::max(most, d);
  }
  // Every spacing within the tolerance of the least one is every spacing within it of the median
  // (|s - median| <= most - least, both differences exact by Sterbenz's lemma when the tolerance is
  // below 1): the answer below without sorting 10^7 spacings.
  if (options.relative_tolerance < 1 && most - least <= options.relative_tolerance * least) {
    check.status = StepCheck::Status::uniform;
    check.step = typical_step(time);
    return check;
  }
  std::vector<double> spacing(n - 1);
  for (std::size_t i = 1; i < n; ++i) spacing[i - 1] = time[i] - time[i - 1];
  // The median spacing, not the mean: one missing sample must not shift the reference so far
  // that a short record's good rows look bad and the gap itself is not the row named.
  std::vector<double> sorted = spacing;
  auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), middle, sorted.end());
  const double median = *middle;
  check.step = median;
  const double allowed = options.relative_tolerance * median;
  for (std::size_t i = 0; i < spacing.size(); ++i) {
    if (std::fabs(spacing[i] - median) > allowed) {
      check.status = StepCheck::Status::not_uniform;
      check.bad_index = i + 1;
      return check;
    }
  }
  check.status = StepCheck::Status::uniform;
  check.step = typical_step(time);  // every spacing agrees; the end points give the most digits
  return check;
}

std::variant<double, Diagnostic> uniform_step(const Record& record, std::string_view time_column,
                                              const UniformStepOptions& options) {
  auto column = complete_column(record, time_column);
  if (auto* d = std::get_if<Diagnostic>(&column)) return std::move(*d);
  const auto& time = *std::get<const Column*>(column);
  const StepCheck check = check_uniform_step(time, options);
  const int field = record.field_of_column(*record.column_index(time_column));
  const std::size_t i = check.bad_index;
  const std::string& path = record.path;
  switch (check.status) {
    case StepCheck::Status::uniform:
      return check.step;
    case StepCheck::Status::too_few_samples:
      return data_diag::too_few_samples(path, time.empty() ? record.header_line : record.line_of_row(0), field,
                                        time_column, time.size());
    case StepCheck::Status::repeats:
      return data_diag::time_repeats(path, record.line_of_row(i), field, time_column, time[i]);
    case StepCheck::Status::goes_backwards:
      return data_diag::time_goes_backwards(path, record.line_of_row(i), field, time_column, time[i - 1], time[i]);
    case StepCheck::Status::not_uniform:
      return data_diag::time_step_not_uniform(path, record.line_of_row(i), field, time_column, time[i] - time[i - 1],
                                              check.step, options.relative_tolerance);
    case StepCheck::Status::not_finite:
      break;  // complete_column has already refused non-finite cells
  }
  return data_diag::bad_cell(path, record.line_of_row(i), field, time_column, cell_fault(time[i]), "");
}

IndexRange time_window(std::span<const double> time, double from, double to) {
  if (time.empty() || !(from <= to)) return {};
  const double fuzz = kTimeFuzzInSteps * std::fabs(typical_step(time));
  const auto first = std::lower_bound(time.begin(), time.end(), from - fuzz);
  const auto last = std::upper_bound(first, time.end(), to + fuzz);
  return {static_cast<std::size_t>(first - time.begin()), static_cast<std::size_t>(last - time.begin())};
}

std::variant<IndexRange, Diagnostic> time_window(const Record& record, std::string_view time_column, double from,
                                                 double to) {
  auto column = complete_column(record, time_column);
  if (auto* d = std::get_if<Diagnostic>(&column)) return std::move(*d);
  const auto& time = *std::get<const Column*>(column);
  const IndexRange rows = time_window(time, from, to);
  if (rows.empty()) return data_diag::empty_time_window(record.path, time_column, from, to, time.front(), time.back());
  return rows;
}

std::vector<double> decimate(std::span<const double> values, std::size_t every, std::size_t first) {
  if (every == 0) every = 1;
  std::vector<double> out;
  if (first >= values.size()) return out;
  out.reserve((values.size() - first + every - 1) / every);
  for (std::size_t i = first; i < values.size(); i += every) out.push_back(values[i]);
  return out;
}

namespace {

// An empty record that still knows the file it came from: names, faults and line numbers, so that
// rows selected or resampled from it are reported at their lines in the file.
Record same_file_as(const Record& record) {
  Record out;
  out.path = record.path;
  out.names = record.names;
  out.first_faults = record.first_faults;
  out.header_line = record.header_line;
  out.line_jumps = record.line_jumps;
  return out;
}

}  // namespace

Record select_rows(const Record& record, IndexRange rows, std::size_t every) {
  if (every == 0) every = 1;
  rows.end = std::min(rows.end, record.rows());
  rows.begin = std::min(rows.begin, rows.end);
  Record out = same_file_as(record);
  out.interpolated_from = record.interpolated_from;
  out.origin_first = record.origin_first + rows.begin * record.origin_stride;
  out.origin_stride = record.origin_stride * every;
  out.columns.reserve(record.columns.size());
  for (const auto& column : record.columns)
    out.columns.push_back(decimate(std::span<const double>(column).subspan(rows.begin, rows.size()), every));
  return out;
}

double resampled_rows(double t0, double t_last, double step) { return std::floor((t_last - t0) / step + kTimeFuzzInSteps) + 1; }

std::size_t max_resampled_rows(std::size_t rows) {
  return rows > kResampledRowsFloor / kResampledRowsPerRow ? rows * kResampledRowsPerRow : kResampledRowsFloor;
}

ResampledSignals resample_linear(std::span<const double> time, const std::vector<Column>& columns,
                                 double step) {
  ResampledSignals out;
  if (time.size() < 2 || !(step > 0) || !std::isfinite(step)) return out;
  for (std::size_t i = 0; i < time.size(); ++i)
    if (!std::isfinite(time[i]) || (i > 0 && !(time[i] > time[i - 1]))) return out;
  for (const auto& column : columns)
    if (column.size() != time.size()) return out;

  const double t0 = time.front();
  const double rows = resampled_rows(t0, time.back(), step);
  if (!(rows <= static_cast<double>(max_resampled_rows(time.size())))) return out;  // also NaN, inf
  const auto count = static_cast<std::size_t>(rows);
  out.time.resize(count);
  for (std::size_t k = 0; k < count; ++k) out.time[k] = t0 + static_cast<double>(k) * step;
  out.columns.assign(columns.size(), std::vector<double>(count));
  std::size_t i = 0;  // time[i] <= t < time[i + 1]
  for (std::size_t k = 0; k < count; ++k) {
    const double t = std::min(out.time[k], time.back());
    while (i + 2 < time.size() && time[i + 1] <= t) ++i;
    const double w = (t - time[i]) / (time[i + 1] - time[i]);
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const double a = columns[c][i];
      const double b = columns[c][i + 1];
      // A faulty neighbour is copied, not blended, so that its fault tag survives for the
      // diagnostic; a weight of exactly 0 or 1 ignores the other neighbour.
      double v;
      if (w == 0) v = a;
      else if (w == 1) v = b;
      else if (std::isnan(a)) v = a;
      else if (std::isnan(b)) v = b;
      else v = a + w * (b - a);
      out.columns[c][k] = v;
    }
  }
  return out;
}

std::variant<Record, Diagnostic> resample_linear(const Record& record, std::string_view time_column, double step) {
  auto column = complete_column(record, time_column);
  if (auto* d = std::get_if<Diagnostic>(&column)) return std::move(*d);
  const auto& time = *std::get<const Column*>(column);
  // Resampling cures a non-uniform step, but not a time that stands still or goes backwards.
  UniformStepOptions any_spacing;
  any_spacing.relative_tolerance = 0.49;
  const StepCheck check = check_uniform_step(time, any_spacing);
  if (check.status != StepCheck::Status::uniform && check.status != StepCheck::Status::not_uniform) {
    if (auto d = uniform_step(record, time_column, any_spacing); std::holds_alternative<Diagnostic>(d))
      return std::get<Diagnostic>(std::move(d));
  }
  if (!(step > 0) || !std::isfinite(step)) return data_diag::invalid_resampling_step(step);
  if (const double rows = resampled_rows(time.front(), time.back(), step); !(rows <= static_cast<double>(max_resampled_rows(time.size()))))
    return data_diag::too_many_resampled_rows(record.path, step, rows, time.size(), max_resampled_rows(time.size()),
                                              (time.back() - time.front()) / static_cast<double>(time.size() - 1));
  ResampledSignals signals = resample_linear(time, record.columns, step);
  Record out = same_file_as(record);
  // The time column is the grid itself, not an interpolation of it.
  signals.columns[*record.column_index(time_column)] = signals.time;
  out.columns.assign(std::make_move_iterator(signals.columns.begin()), std::make_move_iterator(signals.columns.end()));
  // Each new row remembers the earlier of the two rows it lies between (or the row it falls on).
  out.interpolated_from.resize(signals.time.size());
  std::size_t i = 0;
  for (std::size_t k = 0; k < signals.time.size(); ++k) {
    while (i + 1 < time.size() && time[i + 1] <= signals.time[k]) ++i;
    out.interpolated_from[k] = record.original_row(i);
  }
  return out;
}

}  // namespace sidc
