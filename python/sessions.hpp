// What the Python module's `fit`, `select` and `simulate` do, in plain C++ (no Python here): fit and
// select are driver/'s, the same as `sidc fit` and `sidc select` run, with the records given as CSV
// paths or as records already in memory (numpy arrays, converted by python/module.cpp), and the
// report kept instead of printed; simulate checks its names as `sidc simulate` does.
//
// Relies on: driver/ (fit, select, the settings), runtime/ (simulation), report/ (fit.json,
// select.json). The command line's option names are the settings' field names
// (`--validate-samples` is `validate_samples`).
// Guarantees: every problem the CLI reports comes back as its Diagnostics, with the same wording,
// never as an exception or a crash; nothing is written to a file, stdout or stderr; nothing here
// touches Python, so the module runs these with the interpreter lock released.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "diagnostics/diagnostic.hpp"
#include "driver/fit_run.hpp"
#include "driver/select_run.hpp"
#include "ir/compiled_model.hpp"
#include "runtime/simulate/simulate.hpp"

namespace sidc::python {

// A model as the module holds it: compiled, with where it came from (relative data statements are
// taken from `directory`, as `sidc fit` takes them from the model file's folder).
struct LoadedModel {
  CompiledModel compiled;
  std::string path;       // the model file, or `<string>` for text
  std::string directory;  // for relative data paths
};

using driver::RecordInput;
using driver::RecordSettings;

using SelectSettings = driver::SelectSettings;

// Everything one fit produced (driver/fit_run.hpp), with what `sidc fit` would print.
struct FitSession {
  driver::FitRun run;
  std::string report;                  // what `sidc fit` prints on stdout
  std::vector<std::string> warnings;   // what it prints on stderr, rendered, one per entry
};

// Failure: the Diagnostics the CLI would print (one or several, e.g. an --integrate rewrite).
using Failure = std::vector<Diagnostic>;

// `model` is copied in (the session keeps its own, rewritten into the fitted form).
std::variant<std::unique_ptr<FitSession>, Failure> fit_session(const LoadedModel& model, std::vector<RecordInput> records, driver::FitSettings settings);

// What `sidc fit --out DIR --plots DIR --report FILE` writes (an empty name: not that one), checked
// first as the CLI checks it; the files written, or the rendered error.
std::variant<std::vector<std::string>, std::string> save_session(const FitSession& session, const std::string& out, const std::string& plots,
                                                                 const std::string& report);

// fit.json's content (report/fit_files.hpp: fit_document).
nlohmann::ordered_json fit_json_document(const FitSession& session);

// Every group's rows: group and equation (1-based), record (0-based), t, known, fitted, residual, as
// residuals.csv holds them (a streamed fit's rows are evaluated again, block by block).
struct ResidualColumns {
  std::vector<double> group, equation, record, time, known, fitted, residual;
};
std::variant<ResidualColumns, Diagnostic> residual_columns(const FitSession& session);

struct SelectResult {
  nlohmann::ordered_json document;  // select.json's content
  std::string report;               // what `sidc select` prints on stdout
  std::vector<std::string> warnings;
};
std::variant<SelectResult, Failure> select_session(const LoadedModel& model, std::vector<RecordInput> records, const SelectSettings& settings);

struct SimulateRequest {
  std::vector<std::pair<std::string, double>> parameters;  // by name, every parameter of the model
  std::vector<std::pair<std::string, double>> initial;     // "y", "y'", ...: 0 when not given
  std::vector<double> time;
  std::map<std::string, std::vector<double>> inputs;       // on `time`
  std::string method = "rk4", stepper = "dopri5";
  std::optional<int> substeps;
  std::optional<double> tolerance;
};
std::variant<SimulationSummary, Failure> simulate_session(const LoadedModel& model, SimulateRequest request);

}  // namespace sidc::python
