#include "driver/record_settings.hpp"

#include <charconv>
#include <filesystem>

#include "diagnostics/cli_catalogue.hpp"
#include "diagnostics/data_catalogue.hpp"
#include "diagnostics/model_catalogue.hpp"
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

std::variant<SampledRecord, Diagnostic> read_and_bind(RecordInput input, const ir::DataSource& source, const ir::Model& model, const BindOptions& bind,
                                                      const Progress& progress = nullptr, PartShare* share = nullptr) {
  CsvOptions csv;
  csv.share = share;
  if (progress && std::holds_alternative<std::string>(input))
    csv.progress = [&progress, phase = "reading " + std::get<std::string>(input) + " (bytes)"](std::size_t done, std::size_t total) {
      progress(phase, done, total);
    };
  auto record = std::holds_alternative<std::string>(input) ? read_csv(std::get<std::string>(input), csv)
                                                           : std::variant<Record, Diagnostic>(std::get<Record>(std::move(input)));
  if (auto* d = std::get_if<Diagnostic>(&record)) return *d;
  return bind_record(std::get<Record>(std::move(record)), source, model, bind);
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
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    auto bound = read_and_bind(std::move(inputs[i]), out.sources[i], model, out.bind, progress, a.share);
    if (auto* d = std::get_if<Diagnostic>(&bound)) return *d;
    out.records.push_back(std::get<SampledRecord>(std::move(bound)));
    if (!a.keep_outliers)
      for (auto& scan : replace_isolated_outliers(out.records.back(), model)) out.outliers.push_back(std::move(scan));
  }
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
