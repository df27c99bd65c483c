#include "runtime/records/bind_record.hpp"

#include <cmath>
#include <fmt/format.h>
#include <map>

#include "ir/queries.hpp"
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
  std::string time_column;
  if (bound(source, "t")) time_column = column_for(source, "t");
  else if (record.column("t")) time_column = "t";
  else if (record.column("time")) time_column = "time";
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

std::variant<SampledRecord, Diagnostic> bind_record(const Record& record, const ir::DataSource& source,
                                                    const ir::Model& model, const BindOptions& options) {
  return bind(record, nullptr, source, model, options);
}

std::variant<SampledRecord, Diagnostic> bind_record(Record&& record, const ir::DataSource& source, const ir::Model& model,
                                                    const BindOptions& options) {
  return bind(record, &record, source, model, options);
}

}  // namespace sidc
