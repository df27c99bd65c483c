// The files a fit and a selection write (`sidc fit --out DIR`, `sidc select --out DIR`): fit.json,
// residuals.csv, validation.csv and select.json. Formats are documented in docs/cli.md.
//
// Relies on: report/atomic_file.hpp (AtomicFileSet). Guarantees: each file appears whole or not at
// all, and a fit's set appears whole or not at all: every file is written into its temporary
// first and all are renamed in together, so a failed run leaves the previous run's files as they
// were (a fit.json without its residuals.csv, or beside an older one, would read as complete). residuals.csv is written
// as the rows come (a streamed fit evaluates them again block by block), never held in memory.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "ir/compiled_model.hpp"
#include "runtime/select/select.hpp"
#include "runtime/simulate/form_choice.hpp"
#include "runtime/simulate/validate.hpp"
#include "runtime/records/isolated_outliers.hpp"
#include "runtime/refine/refine.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/solve/instrumental_variables.hpp"
#include "runtime/solve/noise_check.hpp"
#include "runtime/solve/local_fit.hpp"
#include "runtime/solve/variable_projection.hpp"
#include "runtime/solve/residual_analysis.hpp"

namespace sidc {

nlohmann::ordered_json fit_json(const FitSummary& summary, const CompiledModel& compiled, const std::string& compiled_path, const FitOptions& options);
// `fitted_records`: the runs past them are of held-out records (`held_out`: true).
nlohmann::ordered_json validation_json(const FitValidation& validation, std::size_t fitted_records);
nlohmann::ordered_json residual_json(const ResidualAnalysis& analysis);
nlohmann::ordered_json instrumental_variables_json(const InstrumentalVariablesSummary& iv);
nlohmann::ordered_json noise_check_json(const NoiseCheck& check);
nlohmann::ordered_json outliers_json(const std::vector<OutlierScan>& scans);
// record,t, then per output: recorded, simulated, error; "" when nothing was simulated.
std::string validation_csv(const FitValidation& validation);

// JSON has no infinity or NaN, and nlohmann writes them as null, which reads back as "absent".
// fit.json and select.json write them as the strings "inf", "-inf" and "nan" instead (docs/cli.md):
// every double of `j` that is not finite is replaced so, in place. A field that is null by design
// ("not computed") stays null.
void non_finite_as_strings(nlohmann::ordered_json& j);

struct FitFiles {
  const CompiledModel& compiled;
  std::string compiled_path;
  const FitSummary& summary;
  const FitOptions& options;
  const std::vector<SampledRecord>& records;
  const std::optional<FitValidation>& validation;  // nullopt: --no-validate
  const ResidualAnalysis& residuals;
  // The form chosen from the data (form_choice.hpp) when the model names none and validation ran;
  // null otherwise (fit.json's `form_choice` is then null; each equation still gives its `form`).
  const FormChoice* form_choice;
  // The output-error refinement (runtime/refine/refine.hpp) when one was asked for; null otherwise
  // (fit.json's `refinement` is then null).
  const RefineSummary* refinement = nullptr;
  // The instrumental-variable estimate (`--estimator iv`, `set estimator = iv`); null otherwise
  // (fit.json's `instrumental_variables` is then null).
  const InstrumentalVariablesSummary* instrumental_variables = nullptr;
  // The local fits (`--local`, `--forget`, `set local`); null otherwise (fit.json's `local` is then
  // null and no local.csv is written).
  const LocalFitSummary* local = nullptr;
  // The values the equation-error fit held the nonlinear parameters at (`param L = 1.2` inside
  // `sin(L*theta)`; variable_projection.hpp); null when the model has none (fit.json's
  // `nonlinear_parameters` is then null).
  const VariableProjectionSummary* nonlinear = nullptr;
  // The noise check (noise_check.hpp); null when it was switched off or the model is static
  // (fit.json's `noise_check` is then null).
  const NoiseCheck* noise_check = nullptr;
  // The outputs' isolated outliers replaced (isolated_outliers.hpp); null when they were kept
  // (`--keep-outliers`: fit.json's `outliers` is then null; an empty list: none found).
  const std::vector<OutlierScan>* outliers = nullptr;
};

// local.csv: one row per window (record, when several, then t_center, each parameter and its
// standard error, G, n and rank per group); a window without estimates (rank < parameters) has
// empty estimate cells. Written as the rows are formatted, never held whole.
bool write_local_csv(std::ostream& out, const LocalFitSummary& local);
nlohmann::ordered_json local_json(const LocalFitSummary& local);

// The whole of fit.json (the fit, validation, residual analysis, form choice, refinement and
// instrumental variables; non-finite numbers as strings): what write_fit_files writes, and what the
// Python module's `to_json()` returns.
nlohmann::ordered_json fit_document(const FitFiles& files);

// Writes DIR/fit.json, DIR/residuals.csv and, when a validation ran, DIR/validation.csv, when local
// fits ran, DIR/local.csv (creating DIR); the paths written, or the Diagnostic of the first failure
// (the previous files untouched). A validation.csv or local.csv of an earlier run is removed when
// this run writes none.
std::variant<std::vector<std::string>, Diagnostic> write_fit_files(const std::string& directory, const FitFiles& files);
// The paths write_fit_files may write in DIR (fit.json, residuals.csv, validation.csv, local.csv).
std::vector<std::string> fit_file_paths(const std::string& directory);

// `outliers`: the outputs' isolated outliers replaced (select.json's `outliers`, as fit.json's); null: kept.
nlohmann::ordered_json select_json(const SelectSummary& summary, const std::string& model_path, const SelectOptions& options,
                                   const std::vector<OutlierScan>* outliers = nullptr);
// DIR/select.json.
std::string select_file_path(const std::string& directory);
// Writes DIR/select.json (creating DIR): its path, or the Diagnostic.
std::variant<std::string, Diagnostic> write_select_file(const std::string& directory, const SelectSummary& summary, const std::string& model_path,
                                                        const SelectOptions& options, const std::vector<OutlierScan>* outliers = nullptr);

}  // namespace sidc
