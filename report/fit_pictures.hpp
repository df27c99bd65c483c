// What `sidc fit` shows beyond the parameters: the residual analysis of each equation group, and
// the pictures and one-page report of issue 5 (`--plots DIR`, `--report FILE`).
//
// Relies on: the fit, the validation runs (runtime/simulate/validate.hpp), the model's `plot` statements
// (runtime/operators/plot_function.hpp) and exact-derivative bindings, report/ for drawing and the page.
// Guarantees: the residual analysis is computed whether or not pictures are asked for (its numbers
// go to the report and to fit.json); figures are drawn only from numbers the fit and the
// validation produced, never re-fitted; a picture that cannot be drawn (gnuplot missing or
// failing) is an error naming the figure and what to install, and no report is written then.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ir/compiled_model.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/solve/residual_correlation.hpp"
#include "runtime/simulate/validate.hpp"

namespace sidc {

// Residual whiteness and input cross-correlation, one per equation group (in FitSummary order).
struct ResidualAnalysis {
  std::vector<ResidualCorrelationSummary> groups;
  std::vector<std::string> notes;  // per group: why it was not computed ("" when it was)
  std::vector<bool> truncated;     // per group: only the first kMaxResidualRows rows were used
};

// The residuals of a long record are read as far as this many rows: the band is then +-0.0026,
// finer than any decision needs, and a streamed fit's second pass stays short.
inline constexpr std::size_t kMaxResidualRows = 1'000'000;

// The residuals come from runtime/solve/residual_correlation.hpp's group_residuals: the fit's own for a
// dense fit, a second pass over row blocks for a streamed one.
ResidualAnalysis analyse_residuals(const ir::Model& model, const FitSummary& summary, const std::vector<SampledRecord>& records,
                                   const FitOptions& options);
std::string residual_report(const ResidualAnalysis& analysis);
nlohmann::ordered_json residual_json(const ResidualAnalysis& analysis);

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
};

// Draws the figures and writes the report; false with `error` set (a message for stderr) when a
// figure cannot be drawn or a file cannot be written. `written` lists the files made.
bool write_fit_pictures(const PictureContext& context, const PictureRequest& request, std::vector<std::string>& written,
                        std::string& error);

}  // namespace sidc
