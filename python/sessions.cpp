// The Python module's fit, select and simulate (sessions.hpp). Fit and select are driver/'s, which
// the command line runs too; simulate is cli/simulate_command.cpp's checks of names, minus the
// record and the files. tests/python/ compares the module's estimates with the CLI's fit.json to
// 1e-12.
#include "python/sessions.hpp"

#include <fmt/format.h>

#include "diagnostics/cli_catalogue.hpp"
#include "report/fit_files.hpp"

namespace sidc::python {
namespace {

Failure failure(Diagnostic d) { return Failure{std::move(d)}; }

// The text `sidc fit` prints, kept: stdout's as one report, stderr's line by line.
driver::FitOutput kept(std::string& report, std::vector<std::string>& warnings) {
  return {[&report](const std::string& text) { report += text; }, [&warnings](const std::string& line) { warnings.push_back(line); }, {}};
}

}  // namespace

std::variant<std::unique_ptr<FitSession>, Failure> fit_session(const LoadedModel& loaded, std::vector<RecordInput> inputs,
                                                               driver::FitSettings settings) {
  auto s = std::make_unique<FitSession>();
  const driver::FitOutput out = kept(s->report, s->warnings);
  auto prepared = driver::prepare_fit(loaded.compiled, loaded.path, loaded.directory, std::move(inputs), std::move(settings), out);
  if (auto* f = std::get_if<driver::Failure>(&prepared)) return f->diagnostics;
  s->run = std::move(*std::get<std::unique_ptr<driver::FitRun>>(prepared));
  if (auto f = driver::run_fit(s->run, out)) return f->diagnostics;
  if (!s->run.summary.is_solution_usable()) s->warnings.push_back(render(cli_diag::rank_deficient()));
  return s;
}

std::variant<std::vector<std::string>, std::string> save_session(const FitSession& session, const std::string& out, const std::string& plots,
                                                                 const std::string& report) {
  const driver::FitRun& run = session.run;
  std::vector<std::string> outputs = out.empty() ? std::vector<std::string>{} : fit_file_paths(out);
  outputs.push_back(report);
  if (auto d = driver::output_overwrites_input(run, outputs)) return render(*d);
  std::vector<std::string> written;
  if (!out.empty()) {
    auto files = driver::write_files(run, out);
    if (auto* d = std::get_if<Diagnostic>(&files)) return render(*d);
    written = std::get<std::vector<std::string>>(std::move(files));
  }
  if (!plots.empty() || !report.empty()) {
    std::string error;
    if (!driver::write_pictures(run, {plots, report}, written, error)) return error;
  }
  return written;
}

nlohmann::ordered_json fit_json_document(const FitSession& session) {
  return fit_document(driver::fit_files_of(session.run));
}

std::variant<ResidualColumns, Diagnostic> residual_columns(const FitSession& session) {
  const driver::FitRun& s = session.run;
  ResidualColumns c;
  for (std::size_t g = 0; g < s.summary.groups.size(); ++g) {
    const auto d = for_each_residual_block(s.compiled.integrated, s.loaded.records, s.options, s.summary, g, [&](std::span<const ResidualRow> rows) {
      for (const auto& r : rows) {
        c.group.push_back(static_cast<double>(g + 1));
        c.equation.push_back(static_cast<double>(r.equation + 1));
        c.record.push_back(static_cast<double>(r.record));
        c.time.push_back(r.time);
        c.known.push_back(r.known);
        c.fitted.push_back(r.known - r.residual);
        c.residual.push_back(r.residual);
      }
      return true;
    });
    if (d) return *d;
  }
  return c;
}

std::variant<SelectResult, Failure> select_session(const LoadedModel& loaded, std::vector<RecordInput> inputs, const SelectSettings& a) {
  SelectSettings settings = a;
  settings.keywords = true;
  auto prepared = driver::prepare_select(loaded.compiled, loaded.path, loaded.directory, std::move(inputs), std::move(settings));
  if (auto* f = std::get_if<driver::Failure>(&prepared)) return f->diagnostics;
  driver::SelectRun& run = *std::get<std::unique_ptr<driver::SelectRun>>(prepared);
  SelectResult out;
  if (auto f = driver::run_select(run, kept(out.report, out.warnings))) return f->diagnostics;
  out.document = select_json(*run.summary, loaded.path, run.options, run.settings.records.keep_outliers ? nullptr : &run.loaded.outliers);
  non_finite_as_strings(out.document);
  return out;
}

std::variant<SimulationSummary, Failure> simulate_session(const LoadedModel& loaded, SimulateRequest a) {
  const ir::Model& model = loaded.compiled.normalized;
  const auto& form = *loaded.compiled.explicit_form;
  if (auto* d = std::get_if<Diagnostic>(&form)) return failure(*d);
  const ExplicitForm& explicit_ = std::get<ExplicitForm>(form);
  SimulateOptions o;
  // cli/simulate_command.cpp: parameter_values, given_initial.
  std::vector<std::optional<double>> values(model.parameters.size());
  std::string names;
  for (const auto& p : model.parameters) names += (names.empty() ? "" : ", ") + p.name;
  for (const auto& [name, v] : a.parameters) {
    const int index = model.parameter_index(name);
    if (index < 0) return failure(cli_diag::no_such_parameter(name, names));
    values[static_cast<std::size_t>(index)] = v;
  }
  std::string missing;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!values[i]) missing += (missing.empty() ? "`" : ", `") + model.parameters[i].name + "`";
    o.parameters.push_back(values[i].value_or(0.0));
  }
  if (!missing.empty()) return failure(cli_diag::missing_parameter_values(missing));
  for (const auto& out : explicit_.outputs) o.initial[out.name].assign(static_cast<std::size_t>(out.order), 0.0);
  for (const auto& [text, v] : a.initial) {
    std::string name = text;
    int order = 0;
    while (!name.empty() && name.back() == '\'') name.pop_back(), ++order;
    auto out = std::find_if(explicit_.outputs.begin(), explicit_.outputs.end(), [&](const auto& output) { return output.name == name; });
    if (out == explicit_.outputs.end()) return failure(cli_diag::not_an_output(fmt::format("{}={}", text, v), name));
    if (order >= out->order) return failure(cli_diag::initial_order_too_high(fmt::format("{}={}", text, v), name, out->order));
    o.initial[name][static_cast<std::size_t>(order)] = v;
  }
  if (a.method == "adaptive") {
    o.method = SimulateOptions::Method::adaptive;
    o.stepper = a.stepper == "cash_karp" ? SimulateOptions::Stepper::cash_karp : SimulateOptions::Stepper::dopri5;
    if (a.tolerance) o.absolute_tolerance = o.relative_tolerance = *a.tolerance;
    if (a.substeps)
      return failure(cli_diag::option_for_other_method("substeps", "rk4", "the adaptive method chooses its own steps; set `tolerance`"));
  } else {
    if (a.tolerance)
      return failure(cli_diag::option_for_other_method("tolerance", "adaptive", "the fixed-step method's accuracy is set by `substeps`"));
    o.substeps = a.substeps.value_or(1);
  }
  for (const auto& s : model.signals)
    if (s.kind == ir::Signal::Kind::input && !s.definition && !a.inputs.count(s.name)) return failure(cli_diag::input_without_values(s.name));
  o.time = std::move(a.time);
  for (auto& [name, samples] : a.inputs) o.inputs[name] = std::move(samples);
  if (!o.time.empty()) o.t0_for_tau = o.time.front();
  if (std::string why; !o.is_valid(&why)) return failure(cli_diag::invalid_options(why));
  auto result = simulate(model, explicit_, o);
  if (auto* d = std::get_if<Diagnostic>(&result)) return failure(*d);
  return std::get<SimulationSummary>(std::move(result));
}

}  // namespace sidc::python
