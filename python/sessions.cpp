// The Python module's fit, select and simulate (sessions.hpp): cli/fit_command.cpp,
// cli/select_command.cpp and cli/simulate_command.cpp step by step, minus argument parsing, files
// and printing. A change to what a command computes belongs in both places; tests/python/ compares
// the module's estimates with the CLI's fit.json to 1e-12, so a drift between them fails there.
#include "python/sessions.hpp"

#include <charconv>
#include <filesystem>
#include <fmt/format.h>

#include "compiler/hold_check_pass.hpp"
#include "compiler/integrate_pass.hpp"
#include "compiler/pipeline.hpp"
#include "compiler/weak_pass.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "diagnostics/model_catalogue.hpp"
#include "ir/queries.hpp"
#include "ir/settings.hpp"
#include "report/fit_files.hpp"
#include "report/text_reports.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/solve/fitted_values.hpp"
#include "runtime/solve/options_from_settings.hpp"

namespace sidc::python {
namespace fs = std::filesystem;
namespace {

Failure failure(Diagnostic d) { return Failure{std::move(d)}; }

// cli/record_options.cpp: evaluation_settings and fit_options, the model's settings overridden.
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

// One record bound as the model's first data statement (`--data`), or the model's own data
// statements when none is given (cli/record_options.cpp: load_records).
std::variant<std::vector<SampledRecord>, Diagnostic> bind_records(const LoadedModel& loaded, const ir::Model& model, std::vector<RecordInput> inputs,
                                                                  const BindOptions& bind) {
  std::vector<SampledRecord> out;
  std::vector<ir::DataSource> sources;
  if (inputs.empty()) {
    for (auto s : model.data) {
      if (fs::path(s.path).is_relative()) s.path = (fs::path(loaded.directory) / s.path).lexically_normal().string();
      inputs.emplace_back(s.path);
      sources.push_back(std::move(s));
    }
    if (inputs.empty()) return diag::no_data_file(Span{loaded.compiled.source, 0, 0});
  } else {
    for (const auto& input : inputs) {
      ir::DataSource s = model.data.empty() ? ir::DataSource{} : model.data.front();
      s.path = std::holds_alternative<std::string>(input) ? std::get<std::string>(input) : std::get<Record>(input).path;
      sources.push_back(std::move(s));
    }
  }
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    std::variant<Record, Diagnostic> record = std::holds_alternative<std::string>(inputs[i])
                                                  ? read_csv(std::get<std::string>(inputs[i]))
                                                  : std::variant<Record, Diagnostic>(std::get<Record>(std::move(inputs[i])));
    if (auto* d = std::get_if<Diagnostic>(&record)) return *d;
    auto bound = bind_record(std::get<Record>(std::move(record)), sources[i], model, bind);
    if (auto* d = std::get_if<Diagnostic>(&bound)) return *d;
    out.push_back(std::get<SampledRecord>(std::move(bound)));
  }
  return out;
}

// cli/form_options.cpp: integration_request.
std::variant<std::optional<ir::IntegrationRequest>, Diagnostic> integration_request(const FitSettings& a) {
  if (!a.form.empty()) {
    ir::IntegrationRequest r;
    request_form(r, a.form);
    return r;
  }
  if (a.integrate.empty()) return std::nullopt;
  ir::IntegrationRequest r;
  if (a.integrate == "auto") {
    r.count = ir::IntegrationRequest::Count::automatic;
    return r;
  }
  int n = -1;
  const auto [end, ec] = std::from_chars(a.integrate.data(), a.integrate.data() + a.integrate.size(), n);
  if (ec != std::errc() || end != a.integrate.data() + a.integrate.size() || n < 0 || n > 8) return diag::integrate_option_invalid(a.integrate);
  r.times = n;
  return r;
}

}  // namespace

std::variant<std::unique_ptr<FitSession>, Failure> fit_session(const LoadedModel& loaded, std::vector<RecordInput> inputs, FitSettings a) {
  auto s = std::make_unique<FitSession>();
  s->model = loaded;
  CompiledModel& compiled = s->model.compiled;
  auto request = integration_request(a);
  if (auto* d = std::get_if<Diagnostic>(&request)) return failure(*d);
  if (const auto& r = std::get<std::optional<ir::IntegrationRequest>>(request)) {
    IntegrateOptions rewrite;
    rewrite.override_request = r;
    Diagnostics problems;
    ir::Model m = weak_pass(integrate_pass(compiled.normalized, rewrite, problems), problems);
    hold_check_pass(m, problems);
    if (problems.has_errors()) return problems.items;
    for (const auto& p : problems.items) s->warnings.push_back(render(p));
    m.form_from_data = false;
    compiled.integrated = std::move(m);
  }
  auto options = fit_options(compiled.integrated, a.records);
  if (auto* d = std::get_if<Diagnostic>(&options)) return failure(*d);
  s->options = std::get<FitOptions>(options);
  auto settings = std::get<EvaluationSettings>(evaluation_settings(compiled.integrated, a.records));
  BindOptions bind = bind_options(settings);
  bind.resample = a.records.resample;
  auto records = bind_records(loaded, compiled.integrated, std::move(inputs), bind);
  if (auto* d = std::get_if<Diagnostic>(&records)) return failure(*d);
  s->records = std::get<std::vector<SampledRecord>>(std::move(records));
  const FitOptions& o = s->options;

  std::string form_report;
  if (compiled.integrated.form_from_data) {  // cli/fit_command.cpp: the form chosen from the data
    if (a.no_validate) {
      form_report = "form: weak, the most accurate on known-truth records (docs/accuracy.md); the model sets none, and with\n"
                    "no_validate there is no simulation to choose one by\n";
      compiled.integrated = rewritten_in_form(compiled.normalized, "weak");
    } else {
      std::vector<ir::Model> rewritten;
      std::vector<std::string> names;
      Diagnostics held;
      for (const std::string f : {"weak", "derivative", "integrated"}) {
        ir::Model m = rewritten_in_form(compiled.normalized, f);
        if (!hold_check_pass(m, held)) continue;
        rewritten.push_back(std::move(m));
        names.push_back(f);
      }
      std::vector<FormCandidate> candidates;
      for (std::size_t i = 0; i < names.size(); ++i) candidates.push_back({names[i], &rewritten[i]});
      s->form_choice = choose_form(candidates, compiled.normalized, *compiled.explicit_form, s->records, o, a.validate_samples);
      form_report = s->form_choice->report();
      compiled.integrated = std::move(rewritten[s->form_choice->chosen]);
    }
  }
  const ir::Model& model = compiled.integrated;
  auto result = fit(model, s->records, o);
  if (auto* d = std::get_if<Diagnostic>(&result)) return failure(*d);
  s->summary = std::get<FitSummary>(std::move(result));
  const FitSummary& summary = s->summary;
  for (const auto& r : summary.operators)
    for (const auto& w : r.warnings) s->warnings.push_back(render(w));
  for (const auto& g : summary.groups)
    for (const auto& w : drift_warnings(model, g.drift)) s->warnings.push_back(render(w));
  for (const auto& w : statistics_warnings(model, summary)) s->warnings.push_back(render(w));
  std::string& report = s->report;
  report = fmt::format("sidc fit: model `{}` ({})\n\n", model.name, loaded.path) + form_report + (form_report.empty() ? "" : "\n") +
           operator_report(summary.operators, o.evaluation, model);
  if (!is_static(model)) report += "\n";
  report += summary.full_report(model);

  auto& iv = s->instrumental_variables;
  if (a.estimator.empty() ? estimator_setting(model.settings) == Estimator::instrumental_variables : a.estimator == "iv") {
    iv = instrumental_variables(model, compiled.normalized, *compiled.explicit_form, s->records, o, summary);
    report += "\n" + iv->full_report();
    if (!iv->is_solution_usable()) s->warnings.push_back(render(cli_diag::instrumental_variables_not_converged(iv->statement)));
  }
  const std::vector<double> fitted_estimate =
      iv && iv->is_solution_usable() ? instrumental_parameter_values(compiled.normalized, *iv, fitted_parameter_values(compiled.normalized, summary, 0.0))
                                     : fitted_parameter_values(compiled.normalized, summary, 0.0);

  auto& refinement = s->refinement;
  if ((a.refine || refine_by_simulation(compiled.normalized.settings)) && summary.is_solution_usable()) {
    if (auto* d = std::get_if<Diagnostic>(&*compiled.explicit_form)) {
      refinement.emplace();
      refinement->message = "the equations cannot be solved for their highest derivatives (" + d->message + "); the equation-error estimate is kept";
    } else {
      RefineOptions ro;
      ro.evaluation = o.evaluation;
      ro.max_samples = a.validate_samples;
      ro.from = o.from;
      ro.to = o.to;
      std::vector<const SampledRecord*> fitted;
      for (const auto& r : s->records) fitted.push_back(&r);
      auto refined = refine(compiled.normalized, std::get<ExplicitForm>(*compiled.explicit_form), fitted_estimate, fitted, ro);
      if (auto* problem = std::get_if<Diagnostic>(&refined)) return failure(*problem);
      refinement = std::get<RefineSummary>(std::move(refined));
    }
    report += "\n" + refinement->report();
    if (!refinement->improved()) s->warnings.push_back("sidc fit: warning: not refined: " + refinement->message);
  }

  if (!a.no_validate) {
    std::vector<SampledRecord> extra;
    for (auto& input : a.validate) {
      std::vector<RecordInput> one;
      one.push_back(std::move(input));
      auto record = bind_records(loaded, model, std::move(one), bind);
      if (auto* d = std::get_if<Diagnostic>(&record)) return failure(*d);
      extra.push_back(std::move(std::get<std::vector<SampledRecord>>(record).front()));
    }
    std::vector<const SampledRecord*> checked;
    for (const auto& r : s->records) checked.push_back(&r);
    for (const auto& r : extra) checked.push_back(&r);
    s->validation = validate_fit(compiled.normalized, *compiled.explicit_form, summary, checked, s->records.size(), o.evaluation, a.validate_samples,
                                 a.initial_state == "record" ? InitialState::record : InitialState::estimate,
                                 refinement && refinement->improved() ? &refinement->values
                                 : iv && iv->is_solution_usable()      ? &fitted_estimate
                                                                       : nullptr,
                                 refinement && refinement->improved() ? "refined by the output error" : "of instrumental variables");
    if (s->validation->failed_record) return failure(cli_diag::cannot_validate(s->validation->failed_path, *s->validation->failed_record));
    report += validation_report(*s->validation, s->records.size());
  }
  s->residuals = analyse_residuals(model, summary, s->records, o);
  report += residual_report(s->residuals);
  if (!summary.is_solution_usable()) s->warnings.push_back(render(cli_diag::rank_deficient()));
  return s;
}

nlohmann::ordered_json fit_json_document(const FitSession& s) {
  static const std::optional<FitValidation> none;
  return fit_document({s.model.compiled, s.model.path, s.summary, s.options, s.records, s.validation ? s.validation : none, s.residuals,
                       s.form_choice ? &*s.form_choice : nullptr, s.refinement ? &*s.refinement : nullptr,
                       s.instrumental_variables ? &*s.instrumental_variables : nullptr});
}

std::variant<ResidualColumns, Diagnostic> residual_columns(const FitSession& s) {
  ResidualColumns c;
  for (std::size_t g = 0; g < s.summary.groups.size(); ++g) {
    const auto d = for_each_residual_block(s.model.compiled.integrated, s.records, s.options, s.summary, g, [&](std::span<const ResidualRow> rows) {
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
  CompiledModel compiled = loaded.compiled;
  const bool weak_by_default = compiled.integrated.form_from_data;
  if (weak_by_default) compiled.integrated = rewritten_in_form(compiled.normalized, "weak");
  const ir::Model& model = compiled.integrated;
  SelectOptions o;
  auto fit = fit_options(model, a.records);
  if (auto* d = std::get_if<Diagnostic>(&fit)) return failure(*d);
  o.fit = std::get<FitOptions>(fit);
  const std::map<std::string, SelectionMethod> methods{
      {"automatic", SelectionMethod::automatic}, {"exact", SelectionMethod::exact}, {"stlsq", SelectionMethod::stlsq}, {"frols", SelectionMethod::frols}};
  o.method = methods.at(a.method);
  const std::map<std::string, SizeRule> rules{{"aic", SizeRule::aic}, {"bic", SizeRule::bic}, {"cv", SizeRule::cv}, {"elbow", SizeRule::elbow}};
  o.rule = rules.at(a.rule);
  o.keep_drift = a.keep_drift;
  o.folds = a.folds;
  o.bootstrap = a.bootstrap;
  o.seed = a.seed;
  o.max_size = a.max_size;
  // cli/select_command.cpp: every name a parameter of the model, none both required and dropped.
  const std::vector<std::string> names = selectable_parameters(model);
  auto known = [&](const std::string& n) { return std::find(names.begin(), names.end(), n) != names.end(); };
  for (const auto& n : a.required) {
    if (!known(n)) return failure(cli_diag::unknown_parameter("require", n, names));
    o.required.push_back(n);
  }
  for (const auto& n : a.dropped) {
    if (!known(n)) return failure(cli_diag::unknown_parameter("drop", n, names));
    if (std::find(a.required.begin(), a.required.end(), n) != a.required.end()) return failure(cli_diag::required_and_dropped(n));
    o.dropped.push_back(n);
  }
  std::map<std::string, std::string> group_of;
  for (const auto& [group, members] : a.groups) {
    for (const auto& item : members) {
      if (!known(item)) return failure(cli_diag::unknown_parameter("group " + group, item, names));
      if (auto [it, fresh] = group_of.emplace(item, group); !fresh) return failure(cli_diag::in_two_groups(item, it->second, group));
    }
    o.groups.emplace_back(group, members);
  }
  if (std::string why; !o.is_valid(&why)) return failure(cli_diag::invalid_options(why));
  auto settings = std::get<EvaluationSettings>(evaluation_settings(model, a.records));
  BindOptions bind = bind_options(settings);
  bind.resample = a.records.resample;
  auto bound = bind_records(loaded, model, std::move(inputs), bind);
  if (auto* d = std::get_if<Diagnostic>(&bound)) return failure(*d);
  const auto records = std::get<std::vector<SampledRecord>>(std::move(bound));
  if (a.simulate) {
    if (equation_groups(model).size() != 1) return failure(cli_diag::simulate_needs_one_group());
    if (auto* d = std::get_if<Diagnostic>(&*compiled.explicit_form)) return failure(cli_diag::simulate_needs_explicit_form(*d));
    o.simulation_error = [&](std::size_t, const std::vector<ParameterIndex>& subset, const std::vector<double>& values) {
      return simulation_rms_error(compiled.normalized, std::get<ExplicitForm>(*compiled.explicit_form), subset, values, records, o.fit.evaluation,
                                  a.simulate_samples);
    };
  }
  auto result = select_operations(model, records, o);
  std::string form_note = weak_by_default ? "form: weak (the model sets none; `set form` chooses another)\n" : "";
  if (auto* d = std::get_if<Diagnostic>(&result); d && weak_by_default && d->code == "weak-form-too-short") {
    form_note = fmt::format("form: integrated (the model sets none, and the weak form cannot be built: {})\n", d->message);
    compiled.integrated = rewritten_in_form(compiled.normalized, "integrated");
    result = select_operations(model, records, o);
  }
  if (auto* d = std::get_if<Diagnostic>(&result)) return failure(*d);
  const SelectSummary& summary = std::get<SelectSummary>(result);
  if (!summary.ok()) return failure(cli_diag::selection_failed(summary.message));
  SelectResult out;
  for (const auto& g : summary.groups)
    for (const auto& d : g.drift)
      out.warnings.push_back(fmt::format("{}: warning: `{}` is nearly a polynomial in t of degree {} over the window (before integration, a + b t holds "
                                         "{:.4f}% of it): a drift absorber{}",
                                         loaded.path, d.column, d.degree, 100 * d.share,
                                         d.set_aside ? "; set aside before the search (give keep_drift or require to search it)" : ""));
  out.report = fmt::format("sidc select: model `{}` ({}), size rule {}\n{}\n", model.name, loaded.path, to_string(o.rule), form_note) + summary.report();
  out.document = select_json(summary, loaded.path, o);
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
  o.inputs = std::move(a.inputs);
  if (!o.time.empty()) o.t0_for_tau = o.time.front();
  if (std::string why; !o.is_valid(&why)) return failure(cli_diag::invalid_options(why));
  auto result = simulate(model, explicit_, o);
  if (auto* d = std::get_if<Diagnostic>(&result)) return failure(*d);
  return std::get<SimulationSummary>(std::move(result));
}

}  // namespace sidc::python
