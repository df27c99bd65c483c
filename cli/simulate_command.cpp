// `sidc simulate`: argument parsing and printing only. The model is solved for its highest
// derivatives by compiler/explicit_form_pass.cpp and integrated by runtime/simulate/simulate.cpp.
//
// Relies on: compiler/load_model.hpp, runtime/records/bind_record.hpp (a record on its uniform grid),
// runtime/solve/options_from_settings.hpp (the model's settings, read as `sidc fit` reads them),
// report/simulation_file.hpp (the CSV), diagnostics/cli_catalogue.hpp (every message). Guarantees:
// every bad option is a one-line `error:` with a `hint:` and exit code 2
// (command line) or 1 (model, record, numbers); the CSV has the record's column names (the time
// column and each output's bound column) and is written atomically; a run that diverges still
// writes its CSV (NaN after the stop) and exits 1 with the sentence saying where.
#include "cli/simulate_command.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli/exit_codes.hpp"
#include "cli/fitted_values.hpp"
#include "cli/number_check.hpp"
#include "cli/output_check.hpp"
#include "compiler/load_model.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "ir/settings.hpp"
#include "report/atomic_file.hpp"
#include "report/simulation_file.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/records/records.hpp"
#include "runtime/simulate/simulate.hpp"
#include "runtime/solve/options_from_settings.hpp"

namespace sidc {
namespace {

namespace fs = std::filesystem;

struct SimulateArguments {
  std::string model;
  std::string params_file;
  std::vector<std::string> params, initial;
  std::string data;
  std::optional<double> t0, t1, step, tolerance;
  std::optional<int> every, substeps;
  std::string method = "rk4", stepper = "dopri5";
  std::string out;
};

std::optional<double> parse_number(std::string_view text) {
  while (!text.empty() && text.front() == ' ') text.remove_prefix(1);
  while (!text.empty() && text.back() == ' ') text.remove_suffix(1);
  double x = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), x);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

struct Failure {
  int code;
  std::string message;
};

// name=value pairs; `what` names the option for messages.
std::variant<std::pair<std::string, double>, Failure> name_value(const std::string& text, const char* option, const char* example) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    return Failure{exit_code::usage_error, render(cli_diag::not_name_value(option, text, example))};
  std::string name = text.substr(0, eq);
  while (!name.empty() && name.back() == ' ') name.pop_back();
  auto value = parse_number(std::string_view(text).substr(eq + 1));
  if (!value)
    return Failure{exit_code::usage_error, render(cli_diag::value_not_finite(option, text, text.substr(eq + 1), example))};
  return std::pair{name, *value};
}

std::variant<std::vector<double>, Failure> parameter_values(const ir::Model& model, const SimulateArguments& a) {
  std::vector<std::optional<double>> values(model.parameters.size());
  auto assign = [&](const std::string& name, double v, bool from_file) -> std::optional<Failure> {
    const int index = model.parameter_index(name);
    if (index < 0) {
      if (from_file) return std::nullopt;  // an integration constant of an integrated fit: not needed
      std::string names;
      for (const auto& p : model.parameters) names += (names.empty() ? "" : ", ") + p.name;
      return Failure{exit_code::usage_error, render(cli_diag::no_such_parameter(name, names))};
    }
    values[static_cast<std::size_t>(index)] = v;
    return std::nullopt;
  };
  if (!a.params_file.empty()) {
    std::string error;
    auto text = read_whole_file(a.params_file, error);
    if (!text) return Failure{exit_code::user_error, error};
    const auto j = nlohmann::json::parse(*text, nullptr, false);
    const auto fitted = fitted_values(j);
    if (!fitted) return Failure{exit_code::user_error, render(cli_diag::not_a_fit_file(a.params_file))};
    for (const auto& [name, value] : *fitted)
      if (auto f = assign(name, value, true)) return *f;
  }
  for (const auto& text : a.params) {
    auto parsed = name_value(text, "--param", "a1=0.5");
    if (auto* f = std::get_if<Failure>(&parsed)) return *f;
    const auto& [name, v] = std::get<std::pair<std::string, double>>(parsed);
    if (auto f = assign(name, v, false)) return *f;
  }
  std::string missing;
  std::vector<double> out;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!values[i]) missing += (missing.empty() ? "`" : ", `") + model.parameters[i].name + "`";
    out.push_back(values[i].value_or(0.0));
  }
  if (!missing.empty())
    return Failure{exit_code::usage_error, render(cli_diag::missing_parameter_values(missing))};
  return out;
}

// "y=1", "y'=0": the output, the derivative order and the value.
std::variant<std::map<std::string, std::vector<std::optional<double>>>, Failure> given_initial(const ExplicitForm& form,
                                                                                                const SimulateArguments& a) {
  std::map<std::string, std::vector<std::optional<double>>> initial;
  for (const auto& text : a.initial) {
    auto parsed = name_value(text, "--initial", "\"y'=0\"");
    if (auto* f = std::get_if<Failure>(&parsed)) return *f;
    auto [name, v] = std::get<std::pair<std::string, double>>(parsed);
    int order = 0;
    while (!name.empty() && name.back() == '\'') name.pop_back(), ++order;
    const auto out = std::find_if(form.outputs.begin(), form.outputs.end(), [&output_name = name](const auto& o) { return o.name == output_name; });
    if (out == form.outputs.end())
      return Failure{exit_code::usage_error, render(cli_diag::not_an_output(text, name))};
    if (order >= out->order) return Failure{exit_code::usage_error, render(cli_diag::initial_order_too_high(text, name, out->order))};
    auto& values = initial[name];
    values.resize(static_cast<std::size_t>(out->order));
    values[static_cast<std::size_t>(order)] = v;
  }
  return initial;
}

int run_simulate(const SimulateArguments& a) {
  if (a.t0 && a.t1 && !(*a.t1 > *a.t0)) return fail(render(cli_diag::end_not_after_start(*a.t1, *a.t0)), exit_code::usage_error);
  if (auto problem = output_problem("-o", a.out, OutputKind::file)) return fail(*problem, exit_code::user_error);
  std::string error, warnings;
  auto compiled = load_compiled_model(a.model, error, warnings);
  std::cerr << warnings;
  if (!compiled) return fail(error, exit_code::user_error);
  const ir::Model& model = compiled->normalized;
  const auto& form = *compiled->explicit_form;
  if (auto* d = std::get_if<Diagnostic>(&form)) return fail(render(*d), exit_code::user_error);
  const ExplicitForm& explicit_ = std::get<ExplicitForm>(form);

  SimulateOptions o;
  auto parameters = parameter_values(model, a);
  if (auto* f = std::get_if<Failure>(&parameters)) return fail(f->message, f->code);
  o.parameters = std::get<std::vector<double>>(parameters);
  auto given = given_initial(explicit_, a);
  if (auto* f = std::get_if<Failure>(&given)) return fail(f->message, f->code);
  if (a.method == "adaptive") {
    o.method = SimulateOptions::Method::adaptive;
    o.stepper = a.stepper == "cash_karp" ? SimulateOptions::Stepper::cash_karp : SimulateOptions::Stepper::dopri5;
    if (a.tolerance) o.absolute_tolerance = o.relative_tolerance = *a.tolerance;
    if (a.substeps)
      return fail(render(cli_diag::option_for_other_method("--substeps", "rk4", "the adaptive method chooses its own steps; set `--tolerance`")), exit_code::usage_error);
  } else {
    if (a.tolerance)
      return fail(render(cli_diag::option_for_other_method("--tolerance", "adaptive", "the fixed-step method's accuracy is set by `--substeps`")), exit_code::usage_error);
    o.substeps = a.substeps.value_or(1);
  }

  // The record: --data, else the model's data statement; none is fine with a time grid.
  std::optional<SampledRecord> record;
  std::string time_name = bound_column(model, "t", "t");
  ir::DataSource source = model.data.empty() ? ir::DataSource{} : model.data.front();
  if (!a.data.empty()) source.path = a.data;
  else if (!model.data.empty() && fs::path(source.path).is_relative())
    source.path = (fs::path(a.model).parent_path() / source.path).lexically_normal().string();
  if (const auto input = input_overwritten_by(a.out, {a.model, source.path, a.params_file}); !input.empty())
    return fail(render(cli_diag::output_is_input(a.out, input)), exit_code::usage_error);
  if (!source.path.empty()) {
    if (a.step) return fail(render(cli_diag::step_with_record()), exit_code::usage_error);
    auto read = read_csv(source.path);
    if (auto* d = std::get_if<Diagnostic>(&read)) return fail(render(*d), exit_code::user_error);
    BindOptions bind = bind_options(evaluation_settings(model.settings));
    bind.every = a.every.value_or(bind.every);
    bind.weights.reset();  // a simulation weighs nothing: the record need not hold the weights column
    auto bound = bind_record(std::get<Record>(read), source, model, bind);
    if (auto* d = std::get_if<Diagnostic>(&bound)) return fail(render(*d), exit_code::user_error);
    record = std::get<SampledRecord>(std::move(bound));
    if (!std::get<Record>(read).column(time_name) && std::get<Record>(read).column("time")) time_name = "time";
  } else if (a.every) {
    return fail(render(cli_diag::every_without_record()), exit_code::usage_error);
  }

  std::size_t first = 0;
  if (record) {
    const auto& time = record->time;
    const double from = a.t0.value_or(time.front()), to = a.t1.value_or(time.back());
    const double tolerance = 1e-9 * std::max(1.0, std::abs(from));
    first = static_cast<std::size_t>(std::lower_bound(time.begin(), time.end(), from - tolerance) - time.begin());
    std::size_t last = first;
    while (last + 1 < time.size() && time[last + 1] <= to + tolerance) ++last;
    if (first >= time.size() || last <= first)
      return fail(render(cli_diag::too_few_samples_between(record->path, from, to, time.front(), time.back())), exit_code::user_error);
    o.time.assign(time.begin() + static_cast<std::ptrdiff_t>(first), time.begin() + static_cast<std::ptrdiff_t>(last) + 1);
    for (const auto& s : model.signals)
      if (s.kind == ir::Signal::Kind::input && !s.definition)
        if (auto it = record->signals.find(s.name); it != record->signals.end())
          o.inputs[s.name].assign(it->second.begin() + static_cast<std::ptrdiff_t>(first), it->second.begin() + static_cast<std::ptrdiff_t>(last) + 1);
  } else {
    if (!a.t1 || !a.step)
      return fail(render(cli_diag::grid_needs_end_and_step()), exit_code::usage_error);
    const double t0 = a.t0.value_or(0.0);
    if (!(*a.t1 > t0)) return fail(render(cli_diag::end_not_after_t0(*a.t1, t0)), exit_code::usage_error);
    // Compared as a double, before it becomes an integer: a step of 1e-300 gives more rows than any
    // integer type holds (the conversion would be undefined).
    const double rows = std::floor((*a.t1 - t0) / *a.step + 1e-9);
    if (!(rows <= 10'000'000.0)) return fail(render(cli_diag::too_many_output_rows(rows, *a.step, t0, *a.t1)), exit_code::usage_error);
    const auto count = static_cast<std::size_t>(rows);
    for (std::size_t i = 0; i <= count; ++i) o.time.push_back(t0 + static_cast<double>(i) * *a.step);
    for (const auto& s : model.signals)
      if (s.kind == ir::Signal::Kind::input && !s.definition)
        return fail(render(cli_diag::input_without_values(s.name)), exit_code::user_error);
  }
  o.t0_for_tau = o.time.front();

  // Initial state: given, else from the record at the first simulated sample, else 0.
  std::map<std::string, std::vector<double>> from_record;
  if (record) {
    // The model's derivative settings, all of them, as `sidc fit` reads them.
    const EvaluationOptions evaluation = evaluation_options(evaluation_settings(model.settings));
    auto estimate = initial_state_from_record(explicit_, *record, evaluation, first);
    if (auto* diag = std::get_if<Diagnostic>(&estimate)) return fail(render(*diag), exit_code::user_error);
    from_record = std::get<std::map<std::string, std::vector<double>>>(std::move(estimate));
  }
  const auto& initial = std::get<std::map<std::string, std::vector<std::optional<double>>>>(given);
  for (const auto& out : explicit_.outputs) {
    auto& values = o.initial[out.name];
    for (int m = 0; m < out.order; ++m) {
      const auto i = static_cast<std::size_t>(m);
      if (auto it = initial.find(out.name); it != initial.end() && it->second[i]) values.push_back(*it->second[i]);
      else if (auto r = from_record.find(out.name); r != from_record.end()) values.push_back(r->second[i]);
      else values.push_back(0.0);
    }
  }
  if (std::string why; !o.is_valid(&why)) return fail(render(cli_diag::invalid_options(why)), exit_code::usage_error);

  auto result = simulate(model, explicit_, o);
  if (auto* d = std::get_if<Diagnostic>(&result)) return fail(render(*d), exit_code::user_error);
  const SimulationSummary& summary = std::get<SimulationSummary>(result);

  const std::string csv = simulation_csv(model, time_name, summary);
  std::string initial_text;
  for (const auto& out : explicit_.outputs)
    for (int m = 0; m < out.order; ++m)
      initial_text += fmt::format("{}{}{} = {}", initial_text.empty() ? "" : ", ", out.name, std::string(static_cast<std::size_t>(m), '\''),
                                  o.initial[out.name][static_cast<std::size_t>(m)]);
  const std::string report = fmt::format("sidc simulate: model `{}`, {} ({}), initial state {}\n{}\n", model.name, a.method == "adaptive" ? "adaptive " + a.stepper : "rk4",
                                         a.method == "adaptive" ? fmt::format("tolerance {}", o.absolute_tolerance) : fmt::format("{} substep{} per sample", o.substeps, o.substeps == 1 ? "" : "s"),
                                         initial_text, summary.brief_report());
  // The CSV is the result (stdout, or the file); the summary and `wrote` are about the run: stderr
  // either way, so that `sidc simulate ... > run.csv` and `-o run.csv` give the same file.
  std::cerr << report;
  if (a.out.empty()) {
    std::cout << csv;
  } else {
    if (!write_file_atomically(a.out, csv, &error)) return fail(render(cli_diag::cannot_write(error)), exit_code::user_error);
    std::cerr << "wrote " << a.out << "\n";
  }
  if (!summary.completed()) {
    return fail(render(cli_diag::simulation_stopped(summary.message)), exit_code::user_error);
  }
  return exit_code::success;
}

}  // namespace

void add_simulate_command(CLI::App& app, int& exit_status) {
  auto a = std::make_shared<SimulateArguments>();
  CLI::App* cmd = app.add_subcommand("simulate", "Solve a model's equations with given parameter values (thesis section 2-4)");
  cmd->add_option("model", a->model, "Model file (.sid) or compiled model (.sidc.json)")->required();
  cmd->add_option("--params", a->params_file, "Parameter values from a fit (DIR/fit.json of `sidc fit --out DIR`; the refined ones when it was refined)");
  // One value per occurrence (or several, comma-separated): a word after it is never taken as a value.
  cmd->add_option("--param", a->params, "Parameter values, NAME=VALUE, repeatable or comma-separated: --param a1=0.5,a2=3 (overrides --params)")
      ->allow_extra_args(false)
      ->delimiter(',');
  cmd->add_option("--data", a->data, "Record giving the time grid, the inputs and the initial state (default: the model's data statement)");
  cmd->add_option("--every", a->every, "Keep every K-th sample of the record")->check(whole_number_check(1));
  cmd->add_option("--t0", a->t0, "Start time (default: the record's first sample, or 0)");
  cmd->add_option("--t1", a->t1, "End time (default: the record's last sample)");
  cmd->add_option("--step", a->step, "Output step, for a run without a record")->check(CLI::PositiveNumber);
  cmd->add_option("--initial", a->initial, "Initial conditions, repeatable or comma-separated: --initial y=1,y'=0 (default: from the record, else 0)")
      ->allow_extra_args(false)
      ->delimiter(',');
  cmd->add_option("--method", a->method, "rk4 (fixed step, the thesis' solver) or adaptive")->check(CLI::IsMember({"rk4", "adaptive"}));
  cmd->add_option("--stepper", a->stepper, "For --method adaptive: dopri5 or cash_karp")->check(CLI::IsMember({"dopri5", "cash_karp"}));
  cmd->add_option("--substeps", a->substeps, "RK4 steps per sample interval (default 1)")->check(whole_number_check(1));
  cmd->add_option("--tolerance", a->tolerance, "Absolute and relative tolerance of the adaptive method (default 1e-9)")->check(CLI::PositiveNumber);
  cmd->add_option("-o,--out", a->out, "Write the simulated outputs to this CSV file (default: stdout)");
  cmd->callback([a, &exit_status] { exit_status = run_simulate(*a); });
}

}  // namespace sidc
