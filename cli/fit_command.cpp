// `sidc fit` (see fit_command.hpp): parses the options, calls the library and prints.
//
// The work is elsewhere: compiler/load_model.hpp loads the model, cli/record_options.hpp the
// records, runtime/solve/fit.hpp fits, runtime/simulate/validate.hpp validates (thesis section
// 2-4), runtime/solve/residual_analysis.hpp tests the residuals, runtime/solve/model_comparison.hpp
// ranks several models, and report/ writes every file, picture and table.
#include "cli/fit_command.hpp"

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>
#include <tuple>
#include <variant>

#include "cli/exit_codes.hpp"
#include "cli/form_options.hpp"
#include "cli/output_check.hpp"
#include "cli/record_options.hpp"
#include "compiler/hold_check_pass.hpp"
#include "compiler/integrate_pass.hpp"
#include "compiler/weak_pass.hpp"
#include "compiler/load_model.hpp"
#include "compiler/pipeline.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "ir/queries.hpp"
#include "ir/settings.hpp"
#include "report/atomic_file.hpp"
#include "report/fit_files.hpp"
#include "report/fit_pictures.hpp"
#include "report/text_reports.hpp"
#include "runtime/refine/refine.hpp"
#include "runtime/simulate/form_choice.hpp"
#include "runtime/simulate/validate.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/solve/fitted_values.hpp"
#include "runtime/solve/instrumental_variables.hpp"
#include "runtime/solve/model_comparison.hpp"
#include "runtime/solve/residual_analysis.hpp"

namespace sidc {
namespace {

namespace fs = std::filesystem;

struct FitArguments {
  std::vector<std::string> compiled;
  FormArguments form_options;         // --integrate, --form (form_options.hpp), over the model's own
  RecordArguments records;            // --data, --from, --to, --every, ... (record_options.hpp)
  std::string out;
  bool no_validate = false;
  std::vector<std::string> validate;  // further records, not used in fitting
  std::size_t validate_samples = 100000;  // compared at most per record (0 = all)
  std::string initial_state = "estimate";  // the validation's start: estimated, or read from the record
  std::string plots;                  // --plots DIR
  std::string report;                 // --report FILE.html
  bool refine = false;                // --refine: output-error refinement after the linear fit
  std::string estimator;              // --estimator least_squares|iv, over the model's `set estimator`
};

// The compiled model to fit when none is named: the only *.sidc.json in the current directory, so
// that `sidc compile model.sid && sidc fit` fits that model. With several, which one is not guessed.
std::variant<std::string, std::string> default_compiled_model() {
  std::vector<std::string> found;
  for (const auto& entry : fs::directory_iterator(fs::current_path()))
    if (entry.is_regular_file() && entry.path().filename().string().ends_with(".sidc.json")) found.push_back(entry.path().filename().string());
  std::sort(found.begin(), found.end());
  if (found.empty()) return std::variant<std::string, std::string>(std::in_place_index<1>, render(cli_diag::no_compiled_model()));
  if (found.size() > 1) return std::variant<std::string, std::string>(std::in_place_index<1>, render(cli_diag::several_compiled_models(found)));
  return std::variant<std::string, std::string>(std::in_place_index<0>, found.front());
}

// One model's fit, reported on stdout; its totals for a comparison table when asked.
int fit_one(const std::string& compiled_path, const FitArguments& a, const std::optional<ir::IntegrationRequest>& request, const std::string& out_dir,
            std::optional<ModelTotals>* totals) {
  std::string error, warnings;
  auto compiled = load_compiled_model(compiled_path, error, warnings);
  std::cerr << warnings;
  if (!compiled) return fail(error, exit_code::user_error);
  if (request) {
    // --integrate/--form: every equation rewritten as `sidc compile` with the same option would.
    IntegrateOptions rewrite;
    rewrite.override_request = request;
    Diagnostics problems;
    ir::Model m = weak_pass(integrate_pass(compiled->normalized, rewrite, problems), problems);
    hold_check_pass(m, problems);
    std::cerr << problems.render_all();
    if (problems.has_errors()) return exit_code::user_error;
    m.form_from_data = false;
    compiled->integrated = std::move(m);
  }
  auto options = fit_options(compiled->integrated, a.records, error);
  if (!options) return fail(error, exit_code::usage_error);
  auto loaded = load_records(*compiled, compiled_path, a.records, error);
  if (!loaded) return fail(error, exit_code::user_error);
  {  // Before any work: no output may overwrite the model, its source or a record.
    std::vector<std::string> inputs{compiled_path, (fs::path(compiled_path).parent_path() / fs::path(compiled->source->name).filename()).string()};
    for (const auto& s : loaded->sources) inputs.push_back(s.path);
    std::vector<std::string> outputs = out_dir.empty() ? std::vector<std::string>{} : fit_file_paths(out_dir);
    outputs.push_back(a.report);
    for (const auto& output : outputs)
      if (const auto input = input_overwritten_by(output, inputs); !input.empty())
        return fail(render(cli_diag::output_is_input(output, input)), exit_code::usage_error);
  }
  const std::vector<SampledRecord>& records = loaded->records;
  std::string form_report;
  std::optional<FormChoice> choice;
  if (compiled->integrated.form_from_data) {
    // The model names no form: each is fitted, and the weak form, the most accurate on known-truth
    // records (docs/accuracy.md), is kept unless another's solved equations follow the record better
    // on every piece of it (form_choice.hpp). Without validation there is nothing to judge them by.
    if (a.no_validate) {
      form_report = "form: weak, the most accurate on known-truth records (docs/accuracy.md); the model sets none, and with\n"
                    "--no-validate there is no simulation to choose one by\n";
      compiled->integrated = rewritten_in_form(compiled->normalized, "weak");
    } else {
      static const std::vector<std::string> forms{"weak", "derivative", "integrated"};
      std::vector<ir::Model> rewritten;
      std::vector<FormCandidate> candidates;
      // A form that leaves a derivative of a held input (the derivative form of `x'`) is no candidate.
      std::vector<std::string> names;
      Diagnostics held;
      for (const auto& f : forms) {
        ir::Model m = rewritten_in_form(compiled->normalized, f);
        if (!hold_check_pass(m, held)) continue;
        rewritten.push_back(std::move(m));
        names.push_back(f);
      }
      for (std::size_t i = 0; i < names.size(); ++i) candidates.push_back({names[i], &rewritten[i]});
      choice = choose_form(candidates, compiled->normalized, *compiled->explicit_form, records, *options, a.validate_samples);
      form_report = choice->report();
      compiled->integrated = std::move(rewritten[choice->chosen]);
    }
  }
  const ir::Model& model = compiled->integrated;

  auto result = fit(model, records, *options);
  if (auto* d = std::get_if<Diagnostic>(&result)) return fail(render(*d), exit_code::user_error);
  const FitSummary& summary = std::get<FitSummary>(result);
  for (const auto& r : summary.operators)
    for (const auto& w : r.warnings) std::cerr << render(w) << "\n";
  for (const auto& g : summary.groups)
    for (const auto& warning : drift_warnings(model, g.drift)) std::cerr << render(warning) << "\n";
  for (const auto& warning : statistics_warnings(model, summary)) std::cerr << render(warning) << "\n";
  std::cout << fmt::format("sidc fit: model `{}` ({})\n\n", model.name, compiled_path) << form_report << (form_report.empty() ? "" : "\n")
            << operator_report(summary.operators, options->evaluation, model);
  if (!is_static(model)) std::cout << "\n";
  std::cout << summary.full_report(model);
  // Instrumental variables (instrumental_variables.hpp): a section after the equation-error report;
  // validation solves with its estimate (or the refined one); residual tests and pictures stay
  // those of the equation-error fit.
  std::optional<InstrumentalVariablesSummary> iv;
  if (a.estimator.empty() ? estimator_setting(model.settings) == Estimator::instrumental_variables : a.estimator == "iv") {
    iv = instrumental_variables(model, compiled->normalized, *compiled->explicit_form, records, *options, summary);
    std::cout << "\n" << iv->full_report();
    if (!iv->is_solution_usable()) std::cerr << render(cli_diag::instrumental_variables_not_converged(iv->statement)) << "\n";
  }

  // The estimate the fit stands by, in the derivative form's parameters: the IV one when it was
  // asked for and usable, else the equation-error one. Refinement starts from it.
  const std::vector<double> fitted_estimate =
      iv && iv->is_solution_usable() ? instrumental_parameter_values(compiled->normalized, *iv, fitted_parameter_values(compiled->normalized, summary, 0.0))
                                     : fitted_parameter_values(compiled->normalized, summary, 0.0);

  // Output-error refinement (issue 15): from that estimate, the parameters whose solved equations
  // reproduce the fitted records best. A failure keeps the estimate it started from and says so.
  std::optional<RefineSummary> refinement;
  if ((a.refine || refine_by_simulation(compiled->normalized.settings)) && summary.is_solution_usable()) {
    if (auto* d = std::get_if<Diagnostic>(&*compiled->explicit_form)) {
      refinement.emplace();
      refinement->message = "the equations cannot be solved for their highest derivatives (" + d->message + "); the equation-error estimate is kept";
    } else {
      RefineOptions ro;
      ro.evaluation = options->evaluation;
      ro.max_samples = a.validate_samples;
      ro.from = options->from;
      ro.to = options->to;
      std::vector<const SampledRecord*> fitted;
      for (const auto& r : records) fitted.push_back(&r);
      auto refined = refine(compiled->normalized, std::get<ExplicitForm>(*compiled->explicit_form), fitted_estimate, fitted, ro);
      if (auto* problem = std::get_if<Diagnostic>(&refined)) return fail(render(*problem), exit_code::user_error);
      refinement = std::get<RefineSummary>(std::move(refined));
    }
    std::cout << "\n" << refinement->report();
    if (!refinement->improved()) std::cerr << "sidc fit: warning: not refined: " << refinement->message << "\n";
  }

  std::optional<FitValidation> validation;
  if (!a.no_validate) {
    // The fitted records, then those given only to be compared with (not copied: records can be long).
    std::vector<SampledRecord> extra;
    for (const auto& path : a.validate) {
      auto record = load_record(model, path, loaded->bind, error);
      if (!record) return fail(error, exit_code::user_error);
      extra.push_back(std::move(*record));
    }
    std::vector<const SampledRecord*> checked;
    for (const auto& r : records) checked.push_back(&r);
    for (const auto& r : extra) checked.push_back(&r);
    validation = validate_fit(compiled->normalized, *compiled->explicit_form, summary, checked, records.size(), options->evaluation,
                              a.validate_samples, a.initial_state == "record" ? InitialState::record : InitialState::estimate,
                              refinement && refinement->improved() ? &refinement->values
                              : iv && iv->is_solution_usable()      ? &fitted_estimate
                                                                    : nullptr,
                              refinement && refinement->improved() ? "refined by the output error" : "of instrumental variables");
    if (validation->failed_record)
      return fail(render(cli_diag::cannot_validate(validation->failed_path, *validation->failed_record)), exit_code::user_error);
    std::cout << validation_report(*validation, records.size());
  }
  const ResidualAnalysis residuals = analyse_residuals(model, summary, records, *options);
  std::cout << residual_report(residuals);

  if (!out_dir.empty()) {
    auto written = write_fit_files(out_dir, {*compiled, compiled_path, summary, *options, records, validation, residuals,
                                             choice ? &*choice : nullptr, refinement ? &*refinement : nullptr, iv ? &*iv : nullptr});
    if (auto* d = std::get_if<Diagnostic>(&written)) return fail(render(*d), exit_code::user_error);
    const auto& paths = std::get<std::vector<std::string>>(written);
    if (paths.size() == 3) std::cerr << "wrote " << paths[0] << ", " << paths[1] << " and " << paths[2] << "\n";
    else std::cerr << "wrote " << paths[0] << " and " << paths[1] << "\n";
  }
  if (!a.plots.empty() || !a.report.empty()) {
    static const std::vector<ValidationSummary> none;
    const PictureContext context{*compiled, compiled_path, summary, *options, records, loaded->sources,
                                 validation ? validation->runs : none, validation ? validation->note : std::string("was switched off (--no-validate)"),
                                 residuals};
    std::vector<std::string> written;
    if (!write_fit_pictures(context, {a.plots, a.report}, written, error)) return fail(error, exit_code::user_error);
    if (!a.plots.empty()) std::cerr << fmt::format("wrote {} pictures into {}\n", written.size() - (a.report.empty() ? 0 : 1), a.plots);
    if (!a.report.empty()) std::cerr << "wrote " << a.report << "\n";
  }
  // Last, so that a model whose files could not be written never ranks in the comparison table.
  if (totals) *totals = model_totals(model.name.empty() ? compiled_path : model.name, model, summary);
  if (!summary.is_solution_usable()) return fail(render(cli_diag::rank_deficient()), exit_code::user_error);
  return exit_code::success;
}

int run_fit(const FitArguments& a) {
  std::vector<std::string> compiled_paths = a.compiled;
  // `--data a.csv b.csv model.sid` once made b.csv and model.sid records; now --data takes one
  // file, and a record where a model belongs is said to be one.
  for (const auto& path : compiled_paths)
    if (fs::path(path).extension() == ".csv") return fail(render(cli_diag::record_as_model(path)), exit_code::usage_error);
  if (compiled_paths.empty()) {
    auto found = default_compiled_model();
    if (found.index() == 1) return fail(std::get<1>(found), exit_code::user_error);
    compiled_paths.push_back(std::get<0>(found));
  }
  // Outputs are checked before the work: a mistyped --out fails now, not after the fit.
  for (const auto& [option, path, kind] : {std::tuple{"--out", a.out, OutputKind::directory}, std::tuple{"--plots", a.plots, OutputKind::directory},
                                           std::tuple{"--report", a.report, OutputKind::file}})
    if (auto problem = output_problem(option, path, kind)) return fail(*problem, exit_code::user_error);
  std::string error;
  const auto request = integration_request(a.form_options, error);
  if (!error.empty()) return fail(error, exit_code::usage_error);
  if (compiled_paths.size() == 1) return fit_one(compiled_paths.front(), a, request, a.out, nullptr);
  if (!a.plots.empty() || !a.report.empty()) return fail(render(cli_diag::pictures_of_several_models(compiled_paths.size())), exit_code::usage_error);
  std::vector<ModelTotals> totals;
  int status = exit_code::success;
  for (const auto& path : compiled_paths) {
    std::optional<ModelTotals> t;
    const std::string out = a.out.empty() ? "" : (fs::path(a.out) / fs::path(path).stem().stem()).string();
    const int code = fit_one(path, a, request, out, &t);
    if (code != exit_code::success && !t) return code;  // could not be fitted at all
    totals.push_back(*t);
    std::cout << "\n";
    status = std::max(status, code == exit_code::user_error ? exit_code::success : code);
  }
  std::cout << comparison_table(compare_models(std::move(totals)));
  return status;
}

}  // namespace

void add_fit_command(CLI::App& app, int& exit_status) {
  auto a = std::make_shared<FitArguments>();
  CLI::App* cmd = app.add_subcommand("fit", "Determine the parameters of a compiled model from records (thesis section 2-1)");
  cmd->add_option("compiled", a->compiled, "Compiled model(s) (.sidc.json), or model files (.sid) to compile first; default: the only compiled model here");
  add_record_options(cmd, a->records);
  add_form_options(cmd, a->form_options);
  cmd->add_option("--out", a->out, "Directory for fit.json, residuals.csv and validation.csv");
  cmd->add_option("--validate-samples", a->validate_samples, "Samples of each record compared by simulation at most, from the start (0 = all)");
  cmd->add_option("--initial-state", a->initial_state,
                  "The validation's initial state: `estimate` (least squares over the record's start, the default) or `record` "
                  "(the first sample and its moving-arc derivatives)")
      ->check(CLI::IsMember({"estimate", "record"}));
  cmd->add_option("--estimator", a->estimator,
                  "`least_squares` (equation error, the default) or `iv` (refined instrumental variables after it); overrides "
                  "`set estimator`")
      ->check(CLI::IsMember({"least_squares", "iv"}));
  cmd->add_option("--plots", a->plots, "Directory for the pictures (SVG and PNG, drawn by gnuplot): outputs, errors, functions, residual tests");
  cmd->add_option("--report", a->report, "Write a one-page HTML report with the fit's tables and pictures to this file");
  cmd->add_flag("--refine", a->refine,
                "Refine the parameters by the output error: Levenberg-Marquardt over the parameters and each record's initial state, "
                "minimising the difference between the records and the solved equations (as `set refine = simulation`)");
  auto* no_validate = cmd->add_flag("--no-validate", a->no_validate, "Do not solve the fitted equations and compare them with the records (thesis section 2-4)");
  cmd->add_option("--validate", a->validate, "Also compare the solved fitted equations with this record, not used in fitting (repeatable)")
      ->allow_extra_args(false)
      ->excludes(no_validate);
  cmd->callback([a, &exit_status] { exit_status = run_fit(*a); });
}

}  // namespace sidc
