#include "cli/record_options.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>

#include "ir/settings.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "diagnostics/data_catalogue.hpp"
#include "runtime/records/records.hpp"
#include "runtime/solve/options_from_settings.hpp"

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
  // One file per --data: a word after it is never taken as a record (`--data a.csv model.sid`).
  cmd->add_option("--data", a.data, "A record to use instead of the model's data statements (CSV); repeat it for several: --data a.csv --data b.csv")
      ->allow_extra_args(false);
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

std::optional<EvaluationSettings> evaluation_settings(const ir::Model& model, const RecordArguments& a, std::string& error) {
  EvaluationSettings e = evaluation_settings(model.settings);
  if (!a.derivative.empty()) {
    auto parsed = parse_moving_arc(a.derivative);
    if (!parsed) {
      error = render(cli_diag::not_a_moving_arc(a.derivative));
      return std::nullopt;
    }
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

std::optional<FitOptions> fit_options(const ir::Model& model, const RecordArguments& a, std::string& error) {
  auto settings = evaluation_settings(model, a, error);
  if (!settings) return std::nullopt;
  FitOptions o = fit_options(*settings);
  if (a.precision == "double") o.least_squares.precision = Precision::double_precision;
  if (a.precision == "extended") o.least_squares.precision = Precision::extended;
  if (std::string why; !o.is_valid(&why)) {
    error = render(cli_diag::invalid_options(why));
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
  auto settings = evaluation_settings(model, a, error);
  if (!settings) return std::nullopt;
  out.bind = bind_options(*settings);
  out.bind.resample = a.resample;
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
