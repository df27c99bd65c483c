#include "cli/record_options.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>

#include "ir/settings.hpp"
#include "diagnostics/model_catalogue.hpp"
#include "runtime/records/records.hpp"

namespace sidc {
namespace fs = std::filesystem;

namespace {

// CLI11's own range check prints the whole range of a double; say it plainly.
const CLI::Validator positive = CLI::Validator(
    [](std::string& value) -> std::string {
      double x = 0;
      const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), x);
      if (ec != std::errc() || end != value.data() + value.size() || !(x > 0) || !std::isfinite(x))
        return "`" + value + "` is not a positive number";
      return {};
    },
    "POSITIVE");

}  // namespace

void add_record_options(CLI::App* cmd, RecordArguments& a) {
  cmd->add_option("--data", a.data, "Record(s) to use instead of the model's data statements (CSV)");
  cmd->add_option("--from", a.from, "Start of the fit window (time)");
  cmd->add_option("--to", a.to, "End of the fit window (time)");
  cmd->add_option("--every", a.every, "Keep every K-th sample")->check(positive);
  cmd->add_option("--step", a.step, "Sampling step, for records without a time column")->check(positive);
  cmd->add_option("--resample", a.resample, "Interpolate the record linearly onto this uniform step")->check(positive);
  cmd->add_option("--derivative", a.derivative, "Moving-arc operator, e.g. \"savgol(7, 3)\"");
  cmd->add_option("--second-derivative", a.second_derivative, "repeated (eq. 3-1.8) or direct")->check(CLI::IsMember({"repeated", "direct"}));
  cmd->add_option("--edges", a.edges, "drop (the thesis) or shorten")->check(CLI::IsMember({"drop", "shorten"}));
  cmd->add_option("--integration", a.integration, "simpson or trapezoid")->check(CLI::IsMember({"simpson", "trapezoid"}));
  cmd->add_option("--precision", a.precision, "Least-squares arithmetic: automatic, double or extended")
      ->check(CLI::IsMember({"automatic", "double", "extended"}));
  cmd->add_option("--weights", a.weights, "A record column weighting each row's residual (eq. 2-1.6)");
}

std::optional<FitOptions> fit_options(const ir::Model& model, const RecordArguments& a, std::string& error) {
  const EvaluationSettings e = evaluation_settings(model.settings);
  FitOptions o;
  MovingArc arc = e.derivative;
  if (!a.derivative.empty()) {
    auto parsed = parse_moving_arc(a.derivative);
    if (!parsed) {
      error = fmt::format("error: `--derivative {}` is not a moving-arc operator\nhint: write e.g. `--derivative \"savgol(7, 3)\"`", a.derivative);
      return std::nullopt;
    }
    arc = *parsed;
  }
  o.evaluation.derivative.window = arc.window;
  o.evaluation.derivative.polyorder = arc.order;
  bool repeated = e.second_derivative_repeated, shorten = e.shorten_edges, trapezoid = e.trapezoid;
  if (!a.second_derivative.empty()) repeated = a.second_derivative == "repeated";
  if (!a.edges.empty()) shorten = a.edges == "shorten";
  if (!a.integration.empty()) trapezoid = a.integration == "trapezoid";
  o.evaluation.derivative.second = repeated ? DerivativeOptions::Second::repeated : DerivativeOptions::Second::direct;
  o.evaluation.derivative.edges = shorten ? DerivativeOptions::Edges::shorten : DerivativeOptions::Edges::drop;
  o.evaluation.integration.rule = trapezoid ? IntegrationOptions::Rule::trapezoid : IntegrationOptions::Rule::simpson;
  if (e.smooth_before_integration) {
    o.evaluation.integration.smoothing_window = e.smooth_before_integration->window;
    o.evaluation.integration.smoothing_polyorder = e.smooth_before_integration->order;
  }
  o.from = a.from ? a.from : e.from;
  o.to = a.to ? a.to : e.to;
  if (a.precision == "double") o.least_squares.precision = Precision::double_precision;
  if (a.precision == "extended") o.least_squares.precision = Precision::extended;
  if (!o.is_valid(&error)) {
    error = "error: " + error;
    return std::nullopt;
  }
  return o;
}

std::optional<SampledRecord> load_record(const ir::Model& model, const std::string& path, const BindOptions& bind, std::string& error) {
  ir::DataSource s = model.data.empty() ? ir::DataSource{} : model.data.front();
  s.path = path;
  auto record = read_csv(s.path);
  if (auto* d = std::get_if<Diagnostic>(&record)) {
    error = render(*d);
    return std::nullopt;
  }
  auto bound = bind_record(std::get<Record>(std::move(record)), s, model, bind);
  if (auto* d = std::get_if<Diagnostic>(&bound)) {
    error = render(*d);
    return std::nullopt;
  }
  return std::get<SampledRecord>(std::move(bound));
}

std::optional<LoadedRecords> load_records(const CompiledModel& compiled, const std::string& compiled_path, const RecordArguments& a,
                                          std::string& error) {
  const ir::Model& model = compiled.integrated;
  LoadedRecords out;
  const fs::path base = fs::path(compiled_path).parent_path();
  if (!a.data.empty()) {
    for (const auto& path : a.data) {
      ir::DataSource s = model.data.empty() ? ir::DataSource{} : model.data.front();
      s.path = path;
      out.sources.push_back(std::move(s));
    }
  } else {
    for (auto s : model.data) {
      if (fs::path(s.path).is_relative()) s.path = (base / s.path).lexically_normal().string();
      out.sources.push_back(std::move(s));
    }
  }
  if (out.sources.empty()) {
    error = render(diag::no_data_file(Span{compiled.source, 0, 0}));
    return std::nullopt;
  }
  const EvaluationSettings e = evaluation_settings(model.settings);
  out.bind.every = a.every.value_or(e.every);
  out.bind.step = a.step ? a.step : e.step;
  out.bind.resample = a.resample;
  if (!a.weights.empty()) out.bind.weights = a.weights;
  else out.bind.weights = e.weights;
  for (const auto& s : out.sources) {
    auto record = read_csv(s.path);
    if (auto* d = std::get_if<Diagnostic>(&record)) {
      error = render(*d);
      return std::nullopt;
    }
    auto bound = bind_record(std::get<Record>(std::move(record)), s, model, out.bind);
    if (auto* d = std::get_if<Diagnostic>(&bound)) {
      error = render(*d);
      return std::nullopt;
    }
    out.records.push_back(std::get<SampledRecord>(std::move(bound)));
  }
  return out;
}

}  // namespace sidc
