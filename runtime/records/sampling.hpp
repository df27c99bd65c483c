// Sampling: is a record uniformly sampled, which rows lie in a time window, every K-th sample,
// and linear resampling onto a uniform grid.
//
// Relies on: records.hpp (a Record and its row -> line map, for diagnostics). Guarantees: no
// function throws or aborts; a time column that is too short, repeats, goes backwards or is not
// uniform yields a Diagnostic naming the first offending row as `file:row:col` (the line in the
// file) and, for a non-uniform step, suggesting --resample. The thesis needs uniform steps: its
// moving-arc derivatives (eqs. 3-1.2 ... 3-1.8) and Simpson's rule assume equidistant data.
#pragma once

#include <cstddef>
#include <span>
#include <string_view>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "runtime/records/records.hpp"

namespace sidc {

// A half-open range [begin, end) of row indices.
struct IndexRange {
  std::size_t begin = 0;
  std::size_t end = 0;
  std::size_t size() const { return end > begin ? end - begin : 0; }
  bool empty() const { return size() == 0; }
};

struct UniformStepOptions {
  // Every spacing t[i+1] - t[i] must lie within this fraction of the typical (median) spacing.
  // 1e-3 accepts times printed with 6 significant digits over a few hundred steps, and catches a
  // missing sample (spacing 2x) or a clock jump anywhere.
  double relative_tolerance = 1e-3;
  bool is_valid() const { return relative_tolerance > 0 && relative_tolerance < 0.5; }
};

struct StepCheck {
  enum class Status { uniform, too_few_samples, not_finite, repeats, goes_backwards, not_uniform };
  Status status = Status::too_few_samples;
  // When uniform: (t[n-1] - t[0]) / (n - 1), the step to use. Otherwise the median spacing.
  double step = 0;
  std::size_t bad_index = 0;  // the first sample (index into time) that breaks the rule
  bool is_uniform() const { return status == Status::uniform; }
};

// The plain check on a vector of times.
StepCheck check_uniform_step(std::span<const double> time, const UniformStepOptions& options = {});

// The step of the record's time column, or a located diagnostic.
std::variant<double, Diagnostic> uniform_step(const Record& record, std::string_view time_column,
                                              const UniformStepOptions& options = {});

// The rows whose time lies in [from, to] (time increasing). Bounds are widened by 1e-6 of a step
// so that 0.82 written as 82 * 0.01 still includes the sample at 0.82.
IndexRange time_window(std::span<const double> time, double from, double to);

// The same on a record's time column; an empty window is an error naming the record's span.
std::variant<IndexRange, Diagnostic> time_window(const Record& record, std::string_view time_column, double from,
                                                 double to);

// values[first], values[first + every], ... (thesis: its Delta = 0.020 record is every other
// sample of the Delta = 0.010 one). every == 0 is treated as 1.
std::vector<double> decimate(std::span<const double> values, std::size_t every, std::size_t first = 0);

// The rows `rows` of a record, every `every`-th one, every column; diagnostics on the result
// still name the lines of the file.
Record select_rows(const Record& record, IndexRange rows, std::size_t every = 1);

struct ResampledSignals {
  std::vector<double> time;                  // time[0] + k * step, k = 0 .. while <= time.back()
  std::vector<std::vector<double>> columns;  // each column linearly interpolated onto `time`
};

// The rows a resampling with `step` makes of a record from t0 to t_last, as a double: a step of
// 1e-300 asks for more rows than any integer type holds, so it is compared before it is converted.
double resampled_rows(double t0, double t_last, double step);
// The most rows a resampling may make of a record of `rows` rows: 16 times as many, or 10^6 when
// that is more (docs/cli.md, --resample). A step of 1e-9 s on a 2 s record would ask for 2*10^9
// rows, 16 GB a column.
inline constexpr std::size_t kResampledRowsPerRow = 16;
inline constexpr std::size_t kResampledRowsFloor = 1'000'000;
std::size_t max_resampled_rows(std::size_t rows);

// Linear interpolation of `columns` (each of time.size()) onto a uniform grid starting at
// time[0]. Requires strictly increasing, finite time, step > 0 and at most max_resampled_rows
// rows; returns empty signals otherwise.
ResampledSignals resample_linear(std::span<const double> time, const std::vector<Column>& columns,
                                 double step);

// The whole record resampled on its time column (which must increase strictly); the time
// column becomes the uniform grid. A faulty cell spreads to the new rows next to it, and the
// diagnostic for them names the faulty cell's line; check the used columns before resampling to
// report faults in the file's own terms. A step making more than max_resampled_rows rows is an
// error.
std::variant<Record, Diagnostic> resample_linear(const Record& record, std::string_view time_column, double step);

}  // namespace sidc
