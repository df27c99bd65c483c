#include "runtime/records/bind_record.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <map>

#include "ir/queries.hpp"
#include "runtime/records/clipping.hpp"
#include "runtime/operators/evaluate.hpp"  // inputs defined by an expression of t, evaluated on the grid

namespace sidc {
namespace {

std::string column_for(const ir::DataSource& source, const std::string& signal) {
  for (const auto& [name, column] : source.bindings)
    if (name == signal) return column;
  return signal;
}

bool bound(const ir::DataSource& source, const std::string& signal) {
  for (const auto& [name, column] : source.bindings)
    if (name == signal) return true;
  return false;
}

// The column bound to `t`, else one named `t` or `time`; "" when there is none.
std::string time_column_of(const Record& record, const ir::DataSource& source) {
  if (bound(source, "t")) return column_for(source, "t");
  if (record.column("t")) return "t";
  if (record.column("time")) return "time";
  return {};
}

// The binding itself. With `owned` (the record is the caller's to give away), a column used once is
// moved out of the record instead of copied: 10^7 rows of t, x, y are 240 MB.
std::variant<SampledRecord, Diagnostic> bind(const Record& record, Record* owned, const ir::DataSource& source,
                                             const ir::Model& model, const BindOptions& options) {
  // How often each column is taken, so that only its last use may move it.
  std::map<const Column*, int> uses;
  const auto take = [&](const Column* column) -> Column {
    if (owned && --uses[column] == 0) {
      const auto index = static_cast<std::size_t>(column - record.columns.data());
      return std::move(owned->columns[index]);
    }
    return *column;
  };
  const auto count_use = [&](const std::string& name) {
    if (const auto* column = record.column(name)) ++uses[column];
  };
  SampledRecord out;
  out.path = record.path;
  const std::size_t rows = record.rows();

  // The time grid.
  const std::string time_column = time_column_of(record, source);
  if (!time_column.empty()) count_use(time_column);
  for (const auto& s : model.signals)
    if (!s.definition) count_use(column_for(source, s.name));
  if (options.weights) count_use(*options.weights);
  Column time;
  if (!time_column.empty()) {
    auto column = complete_column(record, time_column);
    if (auto* d = std::get_if<Diagnostic>(&column)) return *d;
    if (!options.resample) {
      auto step = uniform_step(record, time_column, options.uniform);
      if (auto* d = std::get_if<Diagnostic>(&step)) return *d;
      out.step = std::get<double>(step);
    }
    time = take(std::get<const Column*>(column));
  } else if (options.step || is_static(model)) {
    // A static model's rows are observations, not samples in time: number them 0, 1, 2, ...
    out.step = options.step.value_or(1.0);
    auto& grid = time.owned();
    grid.resize(rows);
    for (std::size_t k = 0; k < rows; ++k) grid[k] = static_cast<double>(k) * out.step;
  } else {
    return data_diag::no_time_column(record.path, record.header_line > 0 ? record.header_line : 1);
  }

  // The signals read from columns.
  std::vector<std::string> names;
  std::vector<Column> columns;
  for (const auto& s : model.signals) {
    if (s.definition) continue;
    const std::string column = column_for(source, s.name);
    auto values = complete_column(record, column);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    names.push_back(s.name);
    columns.push_back(take(std::get<const Column*>(values)));
    out.columns[s.name] = column;
  }

  if (options.weights) {
    auto values = complete_column(record, *options.weights);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    columns.push_back(take(std::get<const Column*>(values)));  // resampled and decimated with the signals
    out.weights_column = *options.weights;
  }

  if (options.resample) {
    if (!(*options.resample > 0) || !std::isfinite(*options.resample)) return data_diag::invalid_resampling_step(*options.resample);
    // Checked before anything is allocated, and before the count becomes an integer.
    if (time.size() >= 2) {
      const double asked = resampled_rows(time.front(), time.back(), *options.resample);
      if (!(asked <= static_cast<double>(max_resampled_rows(time.size()))))
        return data_diag::too_many_resampled_rows(record.path, *options.resample, asked, time.size(), max_resampled_rows(time.size()),
                                                  (time.back() - time.front()) / static_cast<double>(time.size() - 1));
    }
    ResampledSignals r = resample_linear(time, columns, *options.resample);
    time = std::move(r.time);
    columns.assign(std::make_move_iterator(r.columns.begin()), std::make_move_iterator(r.columns.end()));
    out.step = *options.resample;
  }

  const std::size_t every = static_cast<std::size_t>(std::max(1, options.every));
  // Every sample kept: the columns as they are, not copied again.
  const auto kept = [&](Column& values) { return every == 1 ? std::move(values) : Column(decimate(values, every)); };
  out.time = kept(time);
  out.step *= static_cast<double>(every);
  for (std::size_t i = 0; i < names.size(); ++i) out.signals[names[i]] = kept(columns[i]);
  if (options.weights) out.weights = kept(columns.back()).release();  // the one column past the signals

  // Inputs given as expressions of t (the thesis' x = 60 sin 4 pi t), evaluated on the grid.
  for (const auto& s : model.signals) {
    if (!s.definition) continue;
    Evaluator evaluator(out, model, EvaluationOptions{}, FitWindow{0, out.time.size() ? out.time.size() - 1 : 0});
    auto values = evaluator.evaluate(*s.definition);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    out.signals[s.name] = std::get<std::vector<double>>(std::move(values));
    out.columns[s.name] = "(defined in the model)";
  }
  return out;
}

}  // namespace

std::variant<Stretches, Diagnostic> unbroken_stretches(const Record& record, const ir::DataSource& source, const ir::Model& model,
                                                       const BindOptions& options, std::size_t min_rows) {
  const std::string time_column = time_column_of(record, source);
  if (time_column.empty()) return data_diag::no_time_column(record.path, record.header_line > 0 ? record.header_line : 1);
  // The columns read: a missing one is the binding's error, not a gap.
  std::vector<const Column*> read;
  std::vector<std::string> names{time_column};
  for (const auto& s : model.signals)
    if (!s.definition) names.push_back(column_for(source, s.name));
  if (options.weights) names.push_back(*options.weights);
  for (const auto& name : names) {
    const Column* column = record.column(name);
    if (!column) return std::get<Diagnostic>(complete_column(record, name));  // the did-you-mean diagnostic
    read.push_back(column);
  }
  const Column& time = *read.front();
  const std::size_t n = record.rows();
  std::vector<char> good(n);
  for (std::size_t i = 0; i < n; ++i)
    good[i] = std::all_of(read.begin(), read.end(), [i](const Column* c) { return std::isfinite((*c)[i]); });
  Stretches out;
  // A clipped output's samples at its rail are no samples of the system's output either.
  if (!is_static(model))
    for (const auto& s : model.signals) {
      if (s.kind != ir::Signal::Kind::output || s.definition) continue;
      const auto clipped = clipped_samples(*record.column(column_for(source, s.name)));
      for (std::size_t i = 0; i < clipped.size(); ++i)
        if (clipped[i] && good[i]) {
          good[i] = 0;
          ++out.rows_clipped;
        }
    }
  // The typical spacing: the median over neighbouring good rows.
  std::vector<double> spacing;
  for (std::size_t i = 1; i < n; ++i)
    if (good[i] && good[i - 1]) spacing.push_back(time[i] - time[i - 1]);
  if (spacing.empty()) return data_diag::no_stretch_to_fit(record.path);
  const auto middle = spacing.begin() + static_cast<std::ptrdiff_t>(spacing.size() / 2);
  std::nth_element(spacing.begin(), middle, spacing.end());
  const double step = *middle;
  const double allowed = options.uniform.relative_tolerance * std::abs(step);
  IndexRange current{0, 0};
  const auto close = [&](std::size_t end) {
    current.end = end;
    if (!current.empty()) (current.size() >= min_rows ? out.kept : out.short_ones).push_back(current);
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (!good[i]) {
      ++out.rows_left_out;  // the clipped ones counted in rows_clipped too
      close(i);
      current.begin = i + 1;
      continue;
    }
    if (i > current.begin && !(step > 0 && std::abs(time[i] - time[i - 1] - step) <= allowed)) {
      close(i);
      current.begin = i;
    }
  }
  close(n);
  return out;
}

std::variant<SampledRecord, Diagnostic> bind_record(const Record& record, const ir::DataSource& source,
                                                    const ir::Model& model, const BindOptions& options) {
  return bind(record, nullptr, source, model, options);
}

std::variant<SampledRecord, Diagnostic> bind_record(Record&& record, const ir::DataSource& source, const ir::Model& model,
                                                    const BindOptions& options) {
  return bind(record, &record, source, model, options);
}

}  // namespace sidc
