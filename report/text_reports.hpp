// What `sidc fit` prints beyond the fit's own report: the validation by simulation, the residual
// analysis, and the comparison table of several models (thesis Table 4-1.2).
#pragma once

#include <string>

#include "ir/ir.hpp"
#include "runtime/records/clipping.hpp"
#include "runtime/records/isolated_outliers.hpp"
#include "runtime/simulate/validate.hpp"
#include "runtime/solve/model_comparison.hpp"
#include "runtime/solve/residual_analysis.hpp"

namespace sidc {

// Per record: each signal's noise level (noise_level.hpp) and the derivative operators, chosen
// by savgol(auto) with their estimated rms errors, or the one the settings name.
// Noise levels and derivative errors carry the signals' units when the model gives them.
std::string operator_report(const std::vector<OperatorReport>& reports, const EvaluationOptions& options, const ir::Model& model);
// The outputs' isolated outliers replaced (runtime/records/isolated_outliers.hpp): one block per
// record and output, each sample with its time, value, replacement and size; "" when none.
// `keep_option` names the switch that keeps them (`--keep-outliers`, `keep_outliers=True`).
std::string outlier_report(const std::vector<OutlierScan>& scans, const std::string& keep_option);
// The same as one line for stderr, prefixed by `command` ("sidc fit").
std::string outlier_warning(const OutlierScan& scan, const std::string& command, const std::string& keep_option);
// Outputs that look clipped (runtime/records/clipping.hpp): a paragraph each for the report, and
// a line each for stderr prefixed by `command`.
std::string clipping_report(const std::vector<Clipping>& clipped);
std::string clipping_warning(const Clipping& clipped, const std::string& command);
// `fitted_records`: how many of the runs are of fitted records; the rest are held out
// (`--validate`), and each is marked so.
std::string validation_report(const FitValidation& validation, std::size_t fitted_records);
std::string residual_report(const ResidualAnalysis& analysis);
std::string comparison_table(const ModelComparison& comparison);

}  // namespace sidc
