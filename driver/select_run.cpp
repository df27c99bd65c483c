#include "driver/select_run.hpp"

#include <algorithm>
#include <map>

#include <fmt/format.h>

#include "compiler/pipeline.hpp"
#include "ir/fix_parameters.hpp"
#include "runtime/solve/variable_projection.hpp"
#include "diagnostics/cli_catalogue.hpp"

namespace sidc::driver {
namespace {

// An option's name as the face spells it: `--keep-drift` on the command line, `keep_drift` as a keyword.
std::string option_name(const SelectSettings& s, std::string name) {
  if (!s.keywords) return "--" + name;
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

// Every name a parameter of the model, none both required and dropped, none in two groups.
std::optional<Failure> check_names(const ir::Model& model, const SelectSettings& a, SelectOptions& o) {
  const std::vector<std::string> names = selectable_parameters(model);
  auto known = [&](const std::string& n) { return std::find(names.begin(), names.end(), n) != names.end(); };
  for (const auto& n : a.required) {
    if (!known(n)) return failure(cli_diag::unknown_parameter(option_name(a, "require"), n, names), true);
    o.required.push_back(n);
  }
  for (const auto& n : a.dropped) {
    if (!known(n)) return failure(cli_diag::unknown_parameter(option_name(a, "drop"), n, names), true);
    if (std::find(a.required.begin(), a.required.end(), n) != a.required.end()) return failure(cli_diag::required_and_dropped(n), true);
    o.dropped.push_back(n);
  }
  std::map<std::string, std::string> group_of;
  for (const auto& [group, members] : a.groups) {
    for (const auto& item : members) {
      if (!known(item)) return failure(cli_diag::unknown_parameter(option_name(a, "group") + " " + group, item, names), true);
      if (auto [it, fresh] = group_of.emplace(item, group); !fresh) return failure(cli_diag::in_two_groups(item, it->second, group), true);
    }
    o.groups.emplace_back(group, members);
  }
  return std::nullopt;
}

}  // namespace

std::variant<std::unique_ptr<SelectRun>, Failure> prepare_select(
    CompiledModel compiled, std::string model_path, const std::string& directory, std::vector<RecordInput> inputs, SelectSettings settings,
    const std::function<void(const std::string& phase, std::size_t done, std::size_t total)>& progress) {
  auto run = std::make_unique<SelectRun>();
  run->compiled = std::move(compiled);
  run->model_path = std::move(model_path);
  run->settings = std::move(settings);
  const SelectSettings& a = run->settings;
  CompiledModel& c = run->compiled;
  // The model names no form: the weak form, with which selection found the true terms of every
  // known-truth record of docs/accuracy.md up to 1% noise (the candidates change with the subset,
  // so sidc fit's choice by simulation has nothing fixed to compare here).
  run->weak_by_default = c.integrated.form_from_data;
  if (run->weak_by_default) {
    c.integrated = rewritten_in_form(c.normalized, "weak");
    run->form_note = "form: weak (the model sets none; `set form` chooses another)\n";
  }
  const ir::Model& model = c.integrated;
  SelectOptions& o = run->options;
  auto fit = fit_options(model, a.records);
  if (auto* d = std::get_if<Diagnostic>(&fit)) return failure(*d, true);
  o.fit = std::get<FitOptions>(fit);
  o.fit.share = a.share;
  if (a.stream_above) o.fit.stream_above_entries = *a.stream_above;
  if (a.threads > 0) o.fit.stream_threads = a.threads;
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
  if (auto f = check_names(model, a, o)) return *f;
  if (std::string why; !o.is_valid(&why)) return failure(cli_diag::invalid_options(why), true);
  auto loaded = load_records(c, directory, std::move(inputs), a.records, progress);
  if (auto* d = std::get_if<Diagnostic>(&loaded)) return failure(*d);
  run->loaded = std::get<LoadedRecords>(std::move(loaded));
  return run;
}

std::optional<Failure> run_select(SelectRun& run, const FitOutput& out) {
  const SelectSettings& a = run.settings;
  CompiledModel& compiled = run.compiled;
  const ir::Model& model = compiled.integrated;
  SelectOptions& o = run.options;
  const std::vector<SampledRecord>& records = run.loaded.records;
  // Section 2-4's test as a criterion: each size's best subset, solved from the record like the
  // validation of sidc fit, scored by its RMS error E[y] over outputs and records (divergence:
  // infinite). The derivative form is solved, so it needs every parameter of the equations: one
  // equation group only.
  if (a.simulate) {
    if (equation_groups(model).size() != 1) return failure(cli_diag::simulate_needs_one_group(), true);
    if (auto* d = std::get_if<Diagnostic>(&*compiled.explicit_form)) return failure(cli_diag::simulate_needs_explicit_form(*d));
    o.simulation_error = [&compiled, &records, &o, samples = a.simulate_samples](std::size_t, const std::vector<ParameterIndex>& subset,
                                                                                 const std::vector<double>& values) {
      return simulation_rms_error(compiled.normalized, std::get<ExplicitForm>(*compiled.explicit_form), subset, values, records, o.fit.evaluation,
                                  samples);
    };
  }
  // Nonlinear parameters (`param L = 1.2` inside `sin(L*theta)`): held, for every subset, at the
  // values of least equation error of the whole candidate set (variable projection from the guesses).
  if (has_nonlinear_parameters(compiled.normalized)) {
    auto projection = variable_projection(model, records, o.fit);
    if (auto* d = std::get_if<Diagnostic>(&projection)) return failure(*d);
    const VariableProjectionSummary& v = std::get<VariableProjectionSummary>(projection);
    std::string values;  // the projection's values are the guesses where it found nothing better
    for (std::size_t k = 0; k < v.names.size(); ++k) values += fmt::format("{}{} = {:.7g}", k ? ", " : "", v.names[k], v.values[k]);
    run.form_note += fmt::format("nonlinear parameters held for every subset at the values of least equation error of all the candidates "
                                 "(variable projection from the guesses, {} fits): {}\n",
                                 v.fits, values);
    compiled = fix_nonlinear(CompiledModel(compiled), v.held);
  }
  auto result = select_operations(model, records, o);
  if (auto* d = std::get_if<Diagnostic>(&result); d && run.weak_by_default && d->code == "weak-form-too-short") {
    // A record too short for the weak form's subdomains (the 115 samples of thesis section 4-2):
    // the integrated form needs no margin, and is what sidc fit's form choice falls back to there.
    run.form_note = fmt::format("form: integrated (the model sets none, and the weak form cannot be built: {})\n", d->message);
    compiled.integrated = rewritten_in_form(compiled.normalized, "integrated");
    result = select_operations(model, records, o);
  }
  if (auto* d = std::get_if<Diagnostic>(&result)) return failure(*d);
  run.summary = std::get<SelectSummary>(std::move(result));
  const SelectSummary& summary = *run.summary;
  if (!summary.ok()) return failure(cli_diag::selection_failed(summary.message));
  // Drift absorbers are warnings: on stderr too, where a script looks for them.
  for (const auto& g : summary.groups)
    for (const auto& d : g.drift)
      out.warning(fmt::format("{}: warning: `{}` is nearly a polynomial in t of degree {} over the window (before integration, a + b t holds {:.4f}% "
                              "of it): a drift absorber{}",
                              run.model_path, d.column, d.degree, 100 * d.share,
                              d.set_aside ? fmt::format("; set aside before the search (give {} or {} to search it)", option_name(a, "keep-drift"),
                                                        option_name(a, "require"))
                                          : ""));
  for (const auto& c : run.loaded.clipped) out.warning(clipping_warning(c, "sidc select"));
  for (const auto& scan : run.loaded.outliers) out.warning(outlier_warning(scan, "sidc select", a.records.keep_outliers_name));
  const std::string outliers = clipping_report(run.loaded.clipped) + outlier_report(run.loaded.outliers, a.records.keep_outliers_name);
  out.report(fmt::format("sidc select: model `{}` ({}), size rule {}\n{}{}\n", model.name, run.model_path, to_string(o.rule), run.form_note,
                         a.processes.empty() ? "" : a.processes + "\n") +
             run.loaded.notes + (run.loaded.notes.empty() ? "" : "\n") + outliers + (outliers.empty() ? "" : "\n") + summary.report());
  return std::nullopt;
}

}  // namespace sidc::driver
