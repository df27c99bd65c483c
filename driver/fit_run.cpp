#include "driver/fit_run.hpp"

#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "compiler/hold_check_pass.hpp"
#include "compiler/integrate_pass.hpp"
#include "compiler/pipeline.hpp"
#include "compiler/weak_pass.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "ir/fix_parameters.hpp"
#include "ir/queries.hpp"
#include "ir/settings.hpp"
#include "report/atomic_file.hpp"
#include "report/fit_files.hpp"
#include "report/text_reports.hpp"
#include "runtime/solve/fitted_values.hpp"

namespace sidc::driver {
namespace {

// The model names no form: each is fitted, and the weak form, the most accurate on known-truth
// records (docs/accuracy.md), is kept unless another's solved equations follow the record better
// on every piece of it (form_choice.hpp). Without validation there is nothing to judge them by.
std::string choose_the_form(FitRun& run) {
  CompiledModel& compiled = run.compiled;
  if (run.settings.no_validate) {
    compiled.integrated = rewritten_in_form(compiled.normalized, "weak");
    return "form: weak, the most accurate on known-truth records (docs/accuracy.md); the model sets none, and with\n" + run.settings.no_validate_name +
           " there is no simulation to choose one by\n";
  }
  std::vector<ir::Model> rewritten;
  std::vector<std::string> names;
  Diagnostics held;
  for (const std::string form : {"weak", "derivative", "integrated"}) {
    ir::Model m = rewritten_in_form(compiled.normalized, form);
    // A form that leaves a derivative of a held input (the derivative form of `x'`) is no candidate.
    if (!hold_check_pass(m, held)) continue;
    rewritten.push_back(std::move(m));
    names.push_back(form);
  }
  std::vector<FormCandidate> candidates;
  for (std::size_t i = 0; i < names.size(); ++i) candidates.push_back({names[i], &rewritten[i]});
  run.form_choice =
      choose_form(candidates, compiled.normalized, *compiled.explicit_form, run.loaded.records, run.options, run.settings.validate_samples);
  compiled.integrated = std::move(rewritten[run.form_choice->chosen]);
  return run.form_choice->report();
}

// The values the equation-error fit holds the nonlinear parameters at: those of least G from
// their guesses (variable_projection.hpp), in the form it fits (the weak form when the data
// choose it: the first candidate).
std::optional<Failure> project_nonlinear_parameters(FitRun& run, const FitOutput& out) {
  NonlinearParameters& n = *run.nonlinear;
  const ir::Model searched = n.compiled.integrated.form_from_data ? rewritten_in_form(n.compiled.normalized, "weak") : n.compiled.integrated;
  auto projection = variable_projection(searched, run.loaded.records, run.options);
  if (auto* d = std::get_if<Diagnostic>(&projection)) return failure(*d);
  n.projection = std::get<VariableProjectionSummary>(std::move(projection));
  for (const auto& name : n.projection->at_edge)
    out.warning(fmt::format("sidc fit: warning: nonlinear parameter `{}` ended at the edge of the range searched from its guess "
                            "(1/8 to 8 times it): the data may not determine it, or the guess is far off",
                            name));
  // The projection's values are the guesses where it found nothing better.
  n.held = n.projection->held;
  run.compiled = fix_nonlinear(n.compiled, n.held);
  return std::nullopt;
}

}  // namespace

std::vector<double> NonlinearParameters::with_held(const std::vector<double>& linear) const {
  const auto& parameters = compiled.normalized.parameters;
  std::vector<double> out(parameters.size());
  std::size_t next = 0;
  for (std::size_t k = 0; k < out.size(); ++k)
    out[k] = parameters[k].nonlinear ? held[k] : next < linear.size() ? linear[next++] : 0.0;
  return out;
}

std::variant<std::unique_ptr<FitRun>, Failure> prepare_fit(CompiledModel compiled, std::string model_path, const std::string& directory,
                                                           std::vector<RecordInput> inputs, FitSettings settings, const FitOutput& out) {
  auto run = std::make_unique<FitRun>();
  run->compiled = std::move(compiled);
  run->model_path = std::move(model_path);
  run->settings = std::move(settings);
  CompiledModel& c = run->compiled;
  if (run->settings.form) {
    // Every equation rewritten as `sidc compile` with the same option would.
    IntegrateOptions rewrite;
    rewrite.override_request = run->settings.form;
    Diagnostics problems;
    ir::Model m = weak_pass(integrate_pass(c.normalized, rewrite, problems), problems);
    hold_check_pass(m, problems);
    if (problems.has_errors()) return Failure{problems.items};
    for (const auto& p : problems.items) out.warning(render(p));
    m.form_from_data = false;
    c.integrated = std::move(m);
  }
  // Nonlinear parameters: held at their guesses until run_fit searches for better values.
  if (has_nonlinear_parameters(c.normalized) && c.explicit_form) {
    run->nonlinear = NonlinearParameters{c, nonlinear_guesses(c.normalized), std::nullopt};
    c = fix_nonlinear(run->nonlinear->compiled, run->nonlinear->held);
  }
  const FitSettings& f = run->settings;
  if (f.stride != 1 && !f.local && !f.forget && !local_width_setting(c.integrated.settings))
    return failure(cli_diag::stride_without_local_fit(), true);
  if (f.local && f.forget) return failure(cli_diag::local_and_forget(), true);
  if (f.local && !(std::isfinite(*f.local) && *f.local > 0))
    return failure(cli_diag::invalid_options(fmt::format("the local window's width must be a positive number of time units, not {}", *f.local)), true);
  if (f.forget && !(*f.forget > 0 && *f.forget < 1))
    return failure(cli_diag::invalid_options(fmt::format("the forgetting factor must lie strictly between 0 and 1, not {}", *f.forget)), true);
  auto options = fit_options(c.integrated, run->settings.records);
  if (auto* d = std::get_if<Diagnostic>(&options)) return failure(*d, true);
  run->options = std::get<FitOptions>(options);
  if (f.stream_above) run->options.stream_above_entries = *f.stream_above;
  run->options.share = f.share;
  if (f.threads > 0) run->options.stream_threads = f.threads;
  // The projection compares G at trial values; whitened rows would change their metric with every
  // trial (a profile of generalised least squares needs the covariance's determinant as well).
  if (run->nonlinear) {
    run->options.weak_covariance = false;
    run->options.weak_covariance_off = "the model's nonlinear parameters are searched on unweighted rows";
  }
  if (out.progress)
    run->options.progress = [progress = out.progress](std::size_t done, std::size_t total) {
      progress("fitting: rows folded into the triangular factor", done, total);
    };
  auto loaded = load_records(c, directory, std::move(inputs), run->settings.records, out.progress);
  if (auto* d = std::get_if<Diagnostic>(&loaded)) return failure(*d);
  run->loaded = std::get<LoadedRecords>(std::move(loaded));
  return run;
}

std::optional<Failure> run_fit(FitRun& run, const FitOutput& out) {
  CompiledModel& compiled = run.compiled;
  const FitSettings& a = run.settings;
  const FitOptions& o = run.options;
  const std::vector<SampledRecord>& records = run.loaded.records;
  // Local fits asked for: their window checked against the records before any work, and against
  // the fit windows of the form fitted before the global fit (a setting at fault: exit code 2).
  const std::optional<double> width = a.local ? a.local : a.forget ? std::nullopt : local_width_setting(compiled.integrated.settings);
  LocalFitOptions local_options;
  local_options.width = width.value_or(0);
  local_options.stride = a.stride;
  local_options.forget = a.forget;
  if (width)
    if (auto d = check_local_window(compiled.integrated, records, local_options)) return failure(*d, true);
  if (run.nonlinear)
    if (auto f = project_nonlinear_parameters(run, out)) return f;
  const bool form_from_data = compiled.integrated.form_from_data;
  std::string form_report = compiled.integrated.form_from_data ? choose_the_form(run) : "";
  const ir::Model& model = compiled.integrated;
  if (width)
    if (auto d = check_local_window(model, records, local_options, &o)) return failure(*d, true);

  auto result = fit(model, records, o);
  // Without validation the weak form is taken unseen; on a record too short for its subdomains the
  // integrated form, the next most accurate (docs/accuracy.md), is fitted instead of failing.
  if (const auto* d = std::get_if<Diagnostic>(&result); d && d->code == "weak-form-too-short" && form_from_data && !run.form_choice) {
    form_report = fmt::format("form: integrated, the next most accurate on known-truth records (docs/accuracy.md): the model sets\n"
                              "none, with {} there is no simulation to choose one by, and the weak form cannot be fitted:\n  {}\n",
                              a.no_validate_name, d->message);
    compiled.integrated = rewritten_in_form(compiled.normalized, "integrated");
    result = fit(model, records, o);
  }
  if (auto* d = std::get_if<Diagnostic>(&result)) return failure(*d);
  run.summary = std::get<FitSummary>(std::move(result));
  if (run.nonlinear && run.nonlinear->projection) {
    // The intervals with the held values' own uncertainty, in the form fitted (nonlinear_intervals).
    NonlinearParameters& n = *run.nonlinear;
    const std::string form = run.form_choice ? run.form_choice->scores[run.form_choice->chosen].name : form_from_data ? "weak" : "";
    const NonlinearIntervals intervals =
        nonlinear_intervals(form.empty() ? n.compiled.integrated : rewritten_in_form(n.compiled.normalized, form), records, o, n.held, run.summary);
    n.projection->standard_errors = intervals.standard_errors;
    n.projection->interval_note = intervals.note;
  }
  const FitSummary& summary = run.summary;
  for (const auto& r : summary.operators)
    for (const auto& w : r.warnings) out.warning(render(w));
  for (const auto& g : summary.groups)
    for (const auto& w : drift_warnings(model, g.drift)) out.warning(render(w));
  for (const auto& w : statistics_warnings(model, summary)) out.warning(render(w));
  const std::string& keep = a.records.keep_outliers_name;
  for (const auto& c : run.loaded.clipped) out.warning(clipping_warning(c, "sidc fit"));
  for (const auto& scan : run.loaded.outliers) out.warning(outlier_warning(scan, "sidc fit", keep));
  const std::string outliers = clipping_report(run.loaded.clipped) + outlier_report(run.loaded.outliers, keep);
  std::string report = fmt::format("sidc fit: model `{}` ({})\n{}\n", model.name, run.model_path, a.processes.empty() ? "" : a.processes + "\n") + form_report + (form_report.empty() ? "" : "\n") +
                       run.loaded.notes + (run.loaded.notes.empty() ? "" : "\n") + outliers + (outliers.empty() ? "" : "\n") +
                       operator_report(summary.operators, o.evaluation, model);
  if (!is_static(model)) report += "\n";
  out.report(report + summary.full_report(model));
  const bool refine_asked = a.refine || refine_by_simulation(compiled.normalized.settings);
  if (run.nonlinear) {
    // Static models: the equation error is the output error, nothing to refine. Dynamic ones: the
    // equation error is biased on noisy records, the refinement is not.
    const VariableProjectionSummary& v = *run.nonlinear->projection;
    const bool intervals = std::any_of(v.standard_errors.begin(), v.standard_errors.end(), [](double e) { return std::isfinite(e); });
    std::string next;
    const char* them = v.names.size() > 1 ? "them" : "it";
    if (refine_asked && summary.is_solution_usable()) next = fmt::format("The refinement below estimates {} with the others.\n", them);
    else if (!is_static(model))
      next = fmt::format("--refine (or `set refine = simulation`) estimates {} with the others by the output error, free of the equation\n"
                         "error's bias on noisy records.\n", them);
    out.report("\n" + v.report() + next);
    if (!intervals && !(refine_asked && summary.is_solution_usable()))
      out.warning(fmt::format("sidc fit: warning: {} {} held by the equation-error fit without an interval ({}){}",
                              fmt::join(v.names, ", "), v.names.size() > 1 ? "are" : "is", v.interval_note,
                              is_static(model) ? "" : fmt::format(": add --refine to estimate {} with an interval", them)));
  }

  // The noise check (noise_check.hpp): whether the classical intervals hold under the record's noise
  // and whether it biased the estimate, for every dynamic model (a static one's regressors are its
  // inputs, taken as exact).
  if (a.noise_check && !is_static(model)) {
    run.noise_check = check_noise(model, records, o, summary);
    out.report("\n" + run.noise_check->report());
    if (run.noise_check->found_trouble()) out.warning(render(cli_diag::noise_biases_estimates(run.noise_check->statement())));
  }

  // Instrumental variables (instrumental_variables.hpp): a section after the equation-error report;
  // validation solves with its estimate (or the refined one); residual tests and pictures stay
  // those of the equation-error fit.
  auto& iv = run.instrumental_variables;
  if (a.estimator.empty() ? estimator_setting(model.settings) == Estimator::instrumental_variables : a.estimator == "iv") {
    iv = instrumental_variables(model, compiled.normalized, *compiled.explicit_form, records, o, summary);
    out.report("\n" + iv->full_report());
    if (!iv->is_solution_usable()) out.warning(render(cli_diag::instrumental_variables_not_converged(iv->statement)));
  }
  // The estimate the fit stands by, in the derivative form's parameters: the IV one when it was
  // asked for and usable, else the equation-error one. Refinement starts from it.
  const std::vector<double> fitted_estimate =
      iv && iv->is_solution_usable() ? instrumental_parameter_values(compiled.normalized, *iv, fitted_parameter_values(compiled.normalized, summary, 0.0))
                                     : fitted_parameter_values(compiled.normalized, summary, 0.0);

  // Output-error refinement (issue 15): from that estimate, the parameters whose solved equations
  // reproduce the fitted records best. A failure keeps the estimate it started from and says so.
  auto& refinement = run.refinement;
  // With nonlinear parameters it refines the model that has them, from the values the
  // equation-error fit held them at.
  const ir::Model& refined_model = run.nonlinear ? run.nonlinear->compiled.normalized : compiled.normalized;
  const std::variant<ExplicitForm, Diagnostic>& refined_form = run.nonlinear ? *run.nonlinear->compiled.explicit_form : *compiled.explicit_form;
  if (refine_asked && summary.is_solution_usable()) {
    if (auto* d = std::get_if<Diagnostic>(&refined_form)) {
      refinement.emplace();
      refinement->message = "the equations cannot be solved for their highest derivatives (" + d->message + "); the equation-error estimate is kept";
    } else {
      RefineOptions ro;
      ro.evaluation = o.evaluation;
      ro.max_samples = a.refine_samples;
      ro.segments = a.refine_segments;
      ro.from = o.from;
      ro.to = o.to;
      std::vector<const SampledRecord*> fitted;
      for (const auto& r : records) fitted.push_back(&r);
      auto refined = refine(refined_model, std::get<ExplicitForm>(refined_form), run.nonlinear ? run.nonlinear->with_held(fitted_estimate) : fitted_estimate,
                            fitted, ro);
      if (auto* problem = std::get_if<Diagnostic>(&refined)) return failure(*problem);
      refinement = std::get<RefineSummary>(std::move(refined));
    }
    out.report("\n" + refinement->report());
    if (!refinement->improved()) out.warning("sidc fit: warning: not refined: " + refinement->message);
  }

  if (!a.no_validate) {
    // The fitted records, then those given only to be compared with (not copied: records can be long).
    std::vector<SampledRecord>& extra = run.validated_only;
    for (auto& input : run.settings.validate) {
      const std::size_t known = run.loaded.outliers.size();
      auto record = load_record(model, std::move(input), run.loaded.bind, run.settings.records.share,
                                run.settings.records.keep_outliers ? nullptr : &run.loaded.outliers);
      for (std::size_t k = known; k < run.loaded.outliers.size(); ++k)
        out.warning(outlier_warning(run.loaded.outliers[k], "sidc fit", run.settings.records.keep_outliers_name));
      if (auto* d = std::get_if<Diagnostic>(&record)) return failure(*d);
      extra.push_back(std::get<SampledRecord>(std::move(record)));
    }
    run.settings.validate.clear();
    std::vector<const SampledRecord*> checked;
    for (const auto& r : records) checked.push_back(&r);
    for (const auto& r : extra) checked.push_back(&r);
    // The refined values are the refined model's (nonlinear parameters included).
    const bool refined = refinement && refinement->improved();
    run.validation = validate_fit(refined ? refined_model : compiled.normalized, refined ? refined_form : *compiled.explicit_form, summary,
                                  checked, records.size(), o.evaluation, a.validate_samples, a.initial_state,
                                  refined                          ? &refinement->values
                                  : iv && iv->is_solution_usable() ? &fitted_estimate
                                                                   : nullptr,
                                  refined ? "refined by the output error" : "of instrumental variables",
                                  out.progress ? [&out](const std::string& record, std::size_t done, std::size_t total) {
                                    out.progress("validation: solving the fitted equations against " + record + " (samples)", done, total);
                                  } : std::function<void(const std::string&, std::size_t, std::size_t)>());
    if (run.validation->failed_record) return failure(cli_diag::cannot_validate(run.validation->failed_path, *run.validation->failed_record));
    out.report(validation_report(*run.validation, records.size()));
  }
  run.residuals = analyse_residuals(model, summary, records, o);
  out.report(residual_report(run.residuals));

  // Local fits (thesis chapter V): the same rows, window by window along each record.
  if (width || a.forget) {
    if (out.progress)
      local_options.progress = [&out](const std::string& what, std::size_t done, std::size_t total) {
        out.progress("local fits of " + what + " (windows)", done, total);
      };
    auto local = local_fit(model, records, o, local_options);
    if (auto* d = std::get_if<Diagnostic>(&local)) return failure(*d, true);
    run.local = std::get<LocalFitSummary>(std::move(local));
    out.report("\n" + run.local->report());
  }
  return std::nullopt;
}

std::optional<Diagnostic> output_overwrites_input(const FitRun& run, const std::vector<std::string>& outputs) {
  namespace fs = std::filesystem;
  const fs::path folder = fs::path(run.model_path).parent_path();
  std::vector<std::string> inputs{run.model_path, (folder / fs::path(run.compiled.source->name).filename()).string()};
  for (const auto& s : run.loaded.sources) inputs.push_back(s.path);
  for (const auto& output : outputs)
    if (const auto input = input_overwritten_by(output, inputs); !input.empty()) return cli_diag::output_is_input(output, input);
  return std::nullopt;
}

FitFiles fit_files_of(const FitRun& run) {
  return {run.compiled,
          run.model_path,
          run.summary,
          run.options,
          run.loaded.records,
          run.validation,
          run.residuals,
          run.form_choice ? &*run.form_choice : nullptr,
          run.refinement ? &*run.refinement : nullptr,
          run.instrumental_variables ? &*run.instrumental_variables : nullptr,
          run.local ? &*run.local : nullptr,
          run.nonlinear && run.nonlinear->projection ? &*run.nonlinear->projection : nullptr,
          run.noise_check ? &*run.noise_check : nullptr,
          run.settings.records.keep_outliers ? nullptr : &run.loaded.outliers};
}

std::variant<std::vector<std::string>, Diagnostic> write_files(const FitRun& run, const std::string& directory) {
  return write_fit_files(directory, fit_files_of(run));
}

bool write_pictures(const FitRun& run, const PictureRequest& request, std::vector<std::string>& written, std::string& error) {
  static const std::vector<ValidationSummary> none;
  const PictureContext context{run.compiled, run.model_path, run.summary, run.options, run.loaded.records, run.loaded.sources,
                               run.validation ? run.validation->runs : none,
                               run.validation ? run.validation->note : "was switched off (" + run.settings.no_validate_name + ")", run.residuals,
                               run.local ? &*run.local : nullptr};
  return write_fit_pictures(context, request, written, error);
}

}  // namespace sidc::driver
