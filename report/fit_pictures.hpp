// The pictures and one-page report of a fit (`sidc fit --plots DIR`, `--report FILE`).
//
// Relies on: the fit, the validation runs (runtime/simulate/validate.hpp), the model's `plot` statements
// (runtime/operators/plot_function.hpp) and exact-derivative bindings, report/ for drawing and the page.
// Guarantees: figures are drawn only from numbers the fit and the
// validation produced, never re-fitted; a picture that cannot be drawn (gnuplot missing or
// failing) is an error naming the figure and what to install, and no report is written then.
#pragma once

#include <string>
#include <vector>

#include "ir/compiled_model.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/solve/local_fit.hpp"
#include "runtime/solve/residual_analysis.hpp"
#include "runtime/simulate/validate.hpp"

namespace sidc {

struct PictureRequest {
  std::string plots_directory;  // --plots DIR: SVG and PNG of every figure; empty: none
  std::string report_path;      // --report FILE: the HTML page; empty: none
};

struct PictureContext {
  const CompiledModel& compiled;
  std::string compiled_path;
  const FitSummary& summary;
  const FitOptions& options;
  const std::vector<SampledRecord>& records;       // as fitted
  const std::vector<ir::DataSource>& sources;       // their data statements, paths resolved
  const std::vector<ValidationSummary>& validations;  // may be empty
  std::string validation_note;                      // why validation did not run, if it did not
  const ResidualAnalysis& residuals;
  const LocalFitSummary* local = nullptr;           // sidc fit --local: a figure per parameter
};

// Draws the figures and writes the report; false with `error` set (a message for stderr) when a
// figure cannot be drawn or a file cannot be written. `written` lists the files made.
bool write_fit_pictures(const PictureContext& context, const PictureRequest& request, std::vector<std::string>& written,
                        std::string& error);

}  // namespace sidc
