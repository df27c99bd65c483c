#include "driver/record_settings.hpp"

#include <charconv>
#include <filesystem>

#include <fmt/format.h>

#include "diagnostics/cli_catalogue.hpp"
#include "diagnostics/data_catalogue.hpp"
#include "diagnostics/model_catalogue.hpp"
#include "diagnostics/time_text.hpp"
#include "runtime/solve/options_from_settings.hpp"

namespace sidc::driver {
namespace fs = std::filesystem;

std::variant<EvaluationSettings, Diagnostic> evaluation_settings(const ir::Model& model, const RecordSettings& a) {
  EvaluationSettings e = sidc::evaluation_settings(model.settings);
  if (!a.derivative.empty()) {
    auto parsed = parse_moving_arc(a.derivative);
    if (!parsed) return cli_diag::not_a_moving_arc(a.derivative);
    e.derivative = *parsed;
  }
  if (!a.second_derivative.empty()) e.second_derivative_repeated = a.second_derivative == "repeated", e.second_derivative_given = true;
  if (!a.edges.empty()) e.shorten_edges = a.edges == "shorten";
  if (!a.integration.empty()) e.trapezoid = a.integration == "trapezoid";
  if (a.from) e.from = a.from;
  if (a.to) e.to = a.to;
  if (a.every) e.every = *a.every;
  if (a.step) e.step = a.step;
  if (!a.weights.empty()) e.weights = a.weights;
  return e;
}

std::variant<FitOptions, Diagnostic> fit_options(const ir::Model& model, const RecordSettings& a) {
  auto settings = evaluation_settings(model, a);
  if (auto* d = std::get_if<Diagnostic>(&settings)) return *d;
  FitOptions o = sidc::fit_options(std::get<EvaluationSettings>(settings));
  if (a.precision == "double") o.least_squares.precision = Precision::double_precision;
  if (a.precision == "extended") o.least_squares.precision = Precision::extended;
  if (std::string why; !o.is_valid(&why)) return cli_diag::invalid_options(why);
  return o;
}

std::variant<std::optional<ir::IntegrationRequest>, Diagnostic> integration_request(const std::string& integrate, const std::string& form) {
  if (!form.empty()) {  // the same request as --integrate, named by its form
    ir::IntegrationRequest r;
    request_form(r, form);
    return r;
  }
  if (integrate.empty()) return std::nullopt;
  ir::IntegrationRequest r;
  if (integrate == "auto") {
    r.count = ir::IntegrationRequest::Count::automatic;
    return r;
  }
  int n = -1;
  const auto [end, ec] = std::from_chars(integrate.data(), integrate.data() + integrate.size(), n);
  if (ec != std::errc() || end != integrate.data() + integrate.size() || n < 0 || n > 8) return diag::integrate_option_invalid(integrate);
  r.times = n;
  return r;
}

namespace {

// The record's source: the model's first data statement (its column bindings) with `input`'s path.
ir::DataSource source_of(const ir::Model& model, const RecordInput& input) {
  ir::DataSource s = model.data.empty() ? ir::DataSource{} : model.data.front();
  s.path = std::holds_alternative<std::string>(input) ? std::get<std::string>(input) : std::get<Record>(input).path;
  return s;
}

using Progress = std::function<void(const std::string& phase, std::size_t done, std::size_t total)>;

std::variant<Record, Diagnostic> read(RecordInput input, const Progress& progress, PartShare* share) {
  CsvOptions csv;
  csv.share = share;
  if (progress && std::holds_alternative<std::string>(input))
    csv.progress = [&progress, phase = "reading " + std::get<std::string>(input) + " (bytes)"](std::size_t done, std::size_t total) {
      progress(phase, done, total);
    };
  if (std::holds_alternative<std::string>(input)) return read_csv(std::get<std::string>(input), csv);
  return std::get<Record>(std::move(input));
}

std::variant<SampledRecord, Diagnostic> read_and_bind(RecordInput input, const ir::DataSource& source, const ir::Model& model, const BindOptions& bind,
                                                      const Progress& progress = nullptr, PartShare* share = nullptr) {
  auto record = read(std::move(input), progress, share);
  if (auto* d = std::get_if<Diagnostic>(&record)) return *d;
  return bind_record(std::get<Record>(std::move(record)), source, model, bind);
}

std::string lines_of(const Record& record, IndexRange rows) {
  return fmt::format("lines {}-{}", record.line_of_row(rows.begin), record.line_of_row(rows.end - 1));
}

// The record cut at its gaps into unbroken stretches, each bound as a record named by its lines;
// `notes` gets a paragraph saying what was cut and left out.
std::variant<std::vector<SampledRecord>, Diagnostic> split_and_bind(RecordInput input, const ir::DataSource& source, const ir::Model& model,
                                                                    const BindOptions& bind, const Progress& progress, PartShare* share,
                                                                    std::string& notes) {
  auto read_record = read(std::move(input), progress, share);
  if (auto* d = std::get_if<Diagnostic>(&read_record)) return *d;
  const Record& record = std::get<Record>(read_record);
  auto found = unbroken_stretches(record, source, model, bind, kMinStretchRows);
  if (auto* d = std::get_if<Diagnostic>(&found)) return *d;
  const Stretches& stretches = std::get<Stretches>(found);
  if (stretches.kept.empty())
    return data_diag::no_long_stretch(record.path, kMinStretchRows, stretches.short_ones.size());
  std::vector<SampledRecord> out;
  if (stretches.kept.size() == 1 && stretches.kept.front().size() == record.rows()) {
    notes += fmt::format("record {}: no gap to split at: fitted whole\n", record.path);
    auto bound = bind_record(std::get<Record>(std::move(read_record)), source, model, bind);
    if (auto* d = std::get_if<Diagnostic>(&bound)) return *d;
    out.push_back(std::get<SampledRecord>(std::move(bound)));
    return out;
  }
  std::string pieces;
  for (const IndexRange& rows : stretches.kept) {
    Record piece = select_rows(record, rows);
    piece.path = fmt::format("{} ({})", record.path, lines_of(record, rows));
    auto bound = bind_record(std::move(piece), source, model, bind);
    if (auto* d = std::get_if<Diagnostic>(&bound)) return *d;
    const SampledRecord& r = std::get<SampledRecord>(bound);
    pieces += fmt::format("  {}: {} rows, t = {} to {}\n", lines_of(record, rows), rows.size(), time_text(r.time.front(), r.step, 6),
                          time_text(r.time.back(), r.step, 6));
    out.push_back(std::get<SampledRecord>(std::move(bound)));
  }
  notes += fmt::format("record {}: split at its gaps into {} stretches, each fitted as a record of its own (its own\n"
                       "  initial state and integration constants):\n{}",
                       record.path, out.size(), pieces);
  if (const std::size_t faulty = stretches.rows_left_out - stretches.rows_clipped; faulty > 0)
    notes += fmt::format("  left out: {} row{} with a faulty cell in a column the model reads\n", faulty, faulty == 1 ? "" : "s");
  if (stretches.rows_clipped > 0)
    notes += fmt::format("  left out: {} row{} where an output sits at its rail (clipped: a sensor at the end of its range)\n",
                         stretches.rows_clipped, stretches.rows_clipped == 1 ? "" : "s");
  if (!stretches.short_ones.empty()) {
    std::size_t rows = 0;
    for (const auto& s : stretches.short_ones) rows += s.size();
    notes += fmt::format("  left out: {} stretch{} under {} rows ({} rows in all; the first: {})\n", stretches.short_ones.size(),
                         stretches.short_ones.size() == 1 ? "" : "es", kMinStretchRows, rows, lines_of(record, stretches.short_ones.front()));
  }
  return out;
}

}  // namespace

std::variant<LoadedRecords, Diagnostic> load_records(const CompiledModel& compiled, const std::string& directory, std::vector<RecordInput> inputs,
                                                     const RecordSettings& a, const Progress& progress) {
  const ir::Model& model = compiled.integrated;
  LoadedRecords out;
  if (!inputs.empty()) {
    for (const auto& input : inputs) out.sources.push_back(source_of(model, input));
  } else {
    for (auto s : model.data) {
      if (fs::path(s.path).is_relative()) s.path = (fs::path(directory) / s.path).lexically_normal().string();
      inputs.emplace_back(s.path);
      out.sources.push_back(std::move(s));
    }
  }
  if (out.sources.empty()) return diag::no_data_file(Span{compiled.source, 0, 0});
  auto settings = evaluation_settings(model, a);
  if (auto* d = std::get_if<Diagnostic>(&settings)) return *d;
  out.bind = bind_options(std::get<EvaluationSettings>(settings));
  out.bind.resample = a.resample;
  std::vector<ir::DataSource> sources;  // one per record bound: a record split at its gaps gives several
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    std::vector<SampledRecord> bound;
    if (a.split_at_gaps) {
      auto pieces = split_and_bind(std::move(inputs[i]), out.sources[i], model, out.bind, progress, a.share, out.notes);
      if (auto* d = std::get_if<Diagnostic>(&pieces)) return *d;
      bound = std::get<std::vector<SampledRecord>>(std::move(pieces));
    } else {
      auto whole = read_and_bind(std::move(inputs[i]), out.sources[i], model, out.bind, progress, a.share);
      if (auto* d = std::get_if<Diagnostic>(&whole)) return *d;
      bound.push_back(std::get<SampledRecord>(std::move(whole)));
    }
    for (auto& record : bound) {
      for (auto& c : clipped_outputs(record, model)) out.clipped.push_back(std::move(c));
      out.records.push_back(std::move(record));
      sources.push_back(out.sources[i]);
      if (!a.keep_outliers)
        for (auto& scan : replace_isolated_outliers(out.records.back(), model)) out.outliers.push_back(std::move(scan));
    }
  }
  out.sources = std::move(sources);
  return out;
}

std::variant<SampledRecord, Diagnostic> load_record(const ir::Model& model, RecordInput input, const BindOptions& bind, PartShare* share,
                                                    std::vector<OutlierScan>* outliers) {
  const ir::DataSource source = source_of(model, input);
  auto bound = read_and_bind(std::move(input), source, model, bind, nullptr, share);
  if (auto* record = std::get_if<SampledRecord>(&bound); record && outliers)
    for (auto& scan : replace_isolated_outliers(*record, model)) outliers->push_back(std::move(scan));
  return bound;
}

}  // namespace sidc::driver
