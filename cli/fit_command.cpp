// `sidc fit` (see fit_command.hpp): parses the options, calls the library and prints.
//
// The work is elsewhere: compiler/load_model.hpp loads the model, driver/fit_run.hpp makes the fit
// (form, records, fit, instrumental variables, refinement, validation and residual tests, as the
// Python module does), runtime/solve/model_comparison.hpp ranks several models, and report/ writes
// every file and picture.
#include "cli/fit_command.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>
#include <tuple>
#include <variant>

#include "cli/exit_codes.hpp"
#include "cli/form_options.hpp"
#include "cli/number_check.hpp"
#include "cli/output_check.hpp"
#include "cli/progress_line.hpp"
#include "cli/record_options.hpp"
#include "compiler/load_model.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "distributed/session.hpp"
#include "driver/fit_run.hpp"
#include "report/fit_files.hpp"
#include "report/text_reports.hpp"
#include "runtime/solve/model_comparison.hpp"

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
  std::size_t validate_samples = 0;       // compared at most per record (0 = all)
  std::size_t refine_samples = 100000;    // fitted by --refine at most per record (0 = all)
  int refine_segments = 0;                // --refine's shooting segments per record (0 = chosen from the data)
  std::string initial_state = "estimate";  // the validation's start: estimated, or read from the record
  std::string plots;                  // --plots DIR
  std::string report;                 // --report FILE.html
  bool refine = false;                // --refine: output-error refinement after the linear fit
  bool no_noise_check = false;        // --no-noise-check
  std::string estimator;              // --estimator least_squares|iv, over the model's `set estimator`
  std::optional<double> local;        // --local WIDTH: local fits (thesis chapter V), over `set local`
  std::size_t stride = 1;             // --stride S
  std::optional<double> forget;       // --forget LAMBDA
  std::optional<std::size_t> stream_above;  // --stream-above ENTRIES
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
  driver::FitSettings settings;
  settings.records = a.records.settings;
  settings.form = request;
  settings.no_validate = a.no_validate;
  settings.validate.assign(a.validate.begin(), a.validate.end());
  settings.validate_samples = a.validate_samples;
  settings.refine_samples = a.refine_samples;
  settings.refine_segments = a.refine_segments;
  settings.initial_state = a.initial_state == "record" ? InitialState::record : InitialState::estimate;
  settings.refine = a.refine;
  settings.noise_check = !a.no_noise_check;
  settings.estimator = a.estimator;
  settings.local = a.local;
  settings.stride = a.stride;
  settings.forget = a.forget;
  settings.stream_above = a.stream_above;
  // Under mpirun: the rows shared among the ranks, rank 0 alone printing and writing (session.hpp).
  distributed::Session& session = distributed::Session::current();
  settings.share = session.row_share();
  settings.records.share = settings.share;  // each record read by byte ranges
  settings.threads = session.threads_per_rank();
  settings.processes = session.processes_line();
  ProgressLine progress;  // on stderr, only when it is a terminal
  const driver::FitOutput print{[](const std::string& text) { std::cout << text; }, [](const std::string& line) { std::cerr << line << "\n"; },
                                [&progress](const std::string& phase, std::size_t done, std::size_t total) {
                                  std::cout.flush();
                                  progress.update(phase, done, total);
                                }};
  auto prepared = driver::prepare_fit(std::move(*compiled), compiled_path, fs::path(compiled_path).parent_path().string(), record_inputs(a.records),
                                      std::move(settings), print);
  if (auto* f = std::get_if<driver::Failure>(&prepared)) return fail(*f);
  driver::FitRun& run = *std::get<std::unique_ptr<driver::FitRun>>(prepared);
  {  // Before any work: no output may overwrite the model, its source or a record.
    std::vector<std::string> outputs = out_dir.empty() ? std::vector<std::string>{} : fit_file_paths(out_dir);
    outputs.push_back(a.report);
    if (auto d = driver::output_overwrites_input(run, outputs)) return fail(render(*d), exit_code::usage_error);
  }
  if (auto f = driver::run_fit(run, print)) return fail(*f);
  const ir::Model& model = run.compiled.integrated;
  const FitSummary& summary = run.summary;
  // Every rank has fitted, or the job stops here without a file written.
  if (!session.agree(exit_code::success)) return fail(render(diag::error("stopped", {}, session.who_left())), exit_code::user_error);
  if (!out_dir.empty() && session.is_writer()) {
    auto written = driver::write_files(run, out_dir);
    if (auto* d = std::get_if<Diagnostic>(&written)) return fail(render(*d), exit_code::user_error);
    const auto& paths = std::get<std::vector<std::string>>(written);
    std::string list;
    for (std::size_t i = 0; i < paths.size(); ++i) list += (i == 0 ? "" : i + 1 == paths.size() ? " and " : ", ") + paths[i];
    std::cerr << "wrote " << list << "\n";
  }
  if ((!a.plots.empty() || !a.report.empty()) && session.is_writer()) {
    std::vector<std::string> written;
    if (!driver::write_pictures(run, {a.plots, a.report}, written, error)) return fail(error, exit_code::user_error);
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
  cmd->add_option("--out", a->out, "Directory for fit.json, residuals.csv, validation.csv and (with --local or --forget) local.csv");
  cmd->add_option("--validate-samples", a->validate_samples, "Samples of each record compared by simulation at most, from the start (0 = all, the default)")
      ->check(whole_number_check(0));
  cmd->add_option("--refine-samples", a->refine_samples, "Samples of each record the refinement (--refine) fits at most, from the start (default 100000; 0 = all)")
      ->check(whole_number_check(0));
  cmd->add_option("--refine-segments", a->refine_segments,
                  "Shooting segments per record for --refine: 1 = single shooting, N = multiple shooting over N segments, 0 = single unless the start's solution diverges (default)")
      ->check(whole_number_check(0));
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
  cmd->add_option("--local", a->local,
                  "Also fit the model on every window of this width (in time) along each record: slowly varying parameters "
                  "(thesis chapter V); writes local.csv with --out, a picture per parameter with --plots")
      ->check(number_check("WIDTH", [](double v) { return std::isfinite(v) && v > 0; },
                           "WIDTH must be a positive, finite number of time units, e.g. 2.5"));
  cmd->add_option("--stride", a->stride, "Samples from one local window to the next (default 1: every sample)")->check(whole_number_check(1));
  cmd->add_option("--forget", a->forget,
                  "Local estimates by exponential forgetting instead of windows: each sample's rows weighted lambda^age, "
                  "0 < LAMBDA < 1 (memory about 1/(1 - LAMBDA) samples)")
      ->check(number_check("LAMBDA", [](double v) { return v > 0 && v < 1; },
                           "LAMBDA must lie strictly between 0 and 1, e.g. 0.999 (1 forgets nothing: that is the global fit)"));
  cmd->add_option("--stream-above", a->stream_above,
                  "Fold the rows into a triangular factor block by block (streamed QR: memory that does not grow with the record) "
                  "when a group's design has more than this many entries, rows x parameters (default 8000000; 0 = always). "
                  "Under mpirun the ranks share the streamed rows (docs/distributed.md)")
      ->check(whole_number_check(0));
  cmd->add_flag("--refine", a->refine,
                "Refine the parameters by the output error: Levenberg-Marquardt over the parameters and each record's initial state, "
                "minimising the difference between the records and the solved equations (as `set refine = simulation`)");
  cmd->add_flag("--no-noise-check", a->no_noise_check,
                "Do not refit copies of the records with noise added (the noise check: whether the classical intervals hold and the "
                "estimates are unbiased under the record's noise; on by default up to 62,500 samples in all)");
  auto* no_validate = cmd->add_flag("--no-validate", a->no_validate, "Do not solve the fitted equations and compare them with the records (thesis section 2-4)");
  cmd->add_option("--validate", a->validate, "Also compare the solved fitted equations with this record, not used in fitting (repeatable)")
      ->allow_extra_args(false)
      ->excludes(no_validate);
  cmd->callback([a, &exit_status] { exit_status = run_fit(*a); });
}

}  // namespace sidc
