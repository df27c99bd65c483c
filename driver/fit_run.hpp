// `sidc fit`'s work without its command line, for every face that fits (cli/fit_command.cpp, the
// Python module): the model in the requested form, its records, the form chosen from the data when
// the model names none, the equation-error fit, the instrumental variables and the output-error
// refinement when asked for, the validation (thesis section 2-4) and the residual analysis.
//
// Two steps, so that a face can look at what will be read before any work (the command line refuses
// an output that would overwrite an input): prepare_fit, then run_fit. The text of the report goes
// out section by section as it is known, through FitOutput, which the command line prints at once
// and the Python module keeps.
//
// Relies on: compiler/ (the rewrites), runtime/ (everything computed), report/ (the tables printed
// after the fit's own report; the files and pictures of write_files and write_pictures).
// Guarantees: every problem is a Failure (or Diagnostic) holding what the command line prints, never
// an exception; nothing is written to a file but by write_files and write_pictures, and nothing to
// stdout or stderr except through FitOutput.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "driver/failure.hpp"
#include "driver/record_settings.hpp"
#include "report/fit_files.hpp"
#include "report/fit_pictures.hpp"
#include "runtime/refine/refine.hpp"
#include "runtime/simulate/form_choice.hpp"
#include "runtime/simulate/validate.hpp"
#include "runtime/solve/instrumental_variables.hpp"
#include "runtime/solve/local_fit.hpp"
#include "runtime/solve/noise_check.hpp"
#include "runtime/solve/residual_analysis.hpp"
#include "runtime/solve/variable_projection.hpp"

namespace sidc::driver {

// `sidc fit`'s options beyond the records' (docs/cli.md), by their names there.
struct FitSettings {
  RecordSettings records;
  std::optional<ir::IntegrationRequest> form;  // --integrate/--form: every equation rewritten so
  bool no_validate = false;
  std::vector<RecordInput> validate;          // records only compared with, not fitted
  std::size_t validate_samples = 0;           // compared at most per record (0 = all)
  std::size_t refine_samples = 100000;        // fitted by the refinement at most per record (0 = all)
  int refine_segments = 0;                     // shooting segments per record (RefineOptions::segments; 0 = chosen)
  InitialState initial_state = InitialState::estimate;
  bool refine = false;
  bool noise_check = true;                     // the noise check (noise_check.hpp) after the fit's report
  std::string estimator;                      // "", least_squares or iv: over the model's `set estimator`
  std::string no_validate_name = "--no-validate";  // how the face names that option in the report
  // Local fits (runtime/solve/local_fit.hpp, thesis chapter V): windows of `local` (time; over the
  // model's `set local`) every `stride` samples, or with `forget` = lambda recursive estimates.
  std::optional<double> local;
  std::size_t stride = 1;
  std::optional<double> forget;
  // How the fit runs: streamed above this many design entries (FitOptions::stream_above_entries;
  // unset: the default), its rows shared among processes (`share`, not owned; the command line under
  // mpirun) on `threads` threads each (0: one per core), and the line naming the processes, printed
  // under the report's title (empty for one process).
  std::optional<std::size_t> stream_above;
  RowShare* share = nullptr;
  int threads = 0;
  std::string processes;
};

// Where the text goes as it is known: `report` takes what `sidc fit` prints on stdout, `warning` one
// rendered line of what it prints on stderr (without the line's end).
struct FitOutput {
  std::function<void(const std::string&)> report, warning;
  // Optional: how far a long phase is (its name, units done, units in all), for a progress line.
  std::function<void(const std::string& phase, std::size_t done, std::size_t total)> progress;
};

// A model's nonlinear parameters (`param L = 1.2` inside `sin(L*theta)`, ir/fix_parameters.hpp):
// the compiled model as it was, with them, and the values the equation-error fit holds them at
// (found by variable projection from the guesses), for the refinement that estimates them with the
// others.
struct NonlinearParameters {
  CompiledModel compiled;    // its explicit form set (prepare_fit holds only such models)
  std::vector<double> held;  // per parameter of `compiled.normalized`: the value held, NaN for a linear one
  std::optional<VariableProjectionSummary> projection;
  // The equation-error estimate (by `compiled.normalized`'s parameters) with the held values put
  // back: one value per parameter of `normalized`, the refinement's start.
  std::vector<double> with_held(const std::vector<double>& linear) const;
};

// One fit, from its model and records to everything it produced.
struct FitRun {
  // `integrated` is the form fitted (after run_fit: chosen, when the model names none). With
  // nonlinear parameters, every model here holds them at their guesses and has them no more.
  CompiledModel compiled;
  std::optional<NonlinearParameters> nonlinear;
  std::string model_path;  // as named in the report
  FitSettings settings;
  FitOptions options;
  LoadedRecords loaded;
  std::optional<FormChoice> form_choice;
  FitSummary summary;
  std::optional<NoiseCheck> noise_check;
  std::optional<InstrumentalVariablesSummary> instrumental_variables;
  std::optional<RefineSummary> refinement;
  std::optional<FitValidation> validation;
  // The records given only to be compared with (--validate): kept as long as `validation`, whose
  // recorded outputs and grids borrow their columns.
  std::vector<SampledRecord> validated_only;
  ResidualAnalysis residuals;
  std::optional<LocalFitSummary> local;
};

// The model rewritten as `settings.form` asks (its warnings sent to `out`), the fit's options and
// the records (`inputs`, or with none the model's data statements taken from `directory`).
std::variant<std::unique_ptr<FitRun>, Failure> prepare_fit(CompiledModel compiled, std::string model_path, const std::string& directory,
                                                           std::vector<RecordInput> inputs, FitSettings settings, const FitOutput& out);

// Everything else, the report sent to `out` section by section. A rank-deficient fit is no
// failure here: `run.summary.is_solution_usable()` tells, and each face says it its own way.
std::optional<Failure> run_fit(FitRun& run, const FitOutput& out);

// What `--out DIR`, `--plots DIR` and `--report FILE` write, for every face the same way.
// An output that is one of the run's inputs (the model, its source, a record): the error to give
// before anything is written (after prepare_fit, the inputs are known).
std::optional<Diagnostic> output_overwrites_input(const FitRun& run, const std::vector<std::string>& outputs);
// What fit.json and the other files are made of (report/fit_files.hpp), for every face the same.
FitFiles fit_files_of(const FitRun& run);
// fit.json, residuals.csv, validation.csv and local.csv into `directory` (report/fit_files.hpp): the paths written.
std::variant<std::vector<std::string>, Diagnostic> write_files(const FitRun& run, const std::string& directory);
// The pictures and the HTML report (report/fit_pictures.hpp); false with `error` (rendered).
bool write_pictures(const FitRun& run, const PictureRequest& request, std::vector<std::string>& written, std::string& error);

}  // namespace sidc::driver
