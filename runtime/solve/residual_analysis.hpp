// The residual analysis of a fit: whiteness of each equation group's residuals and their
// cross-correlation with each input (runtime/solve/residual_correlation.hpp), computed for every
// `sidc fit` whether or not pictures are asked for; its numbers go to the report and to fit.json.
//
// Relies on: group_residuals (the fit's own residuals for a dense fit, a second pass over row
// blocks for a streamed one). Guarantees: one entry per group in FitSummary order; a group whose
// residuals could not be had carries a note saying why instead of numbers.
#pragma once

#include <string>
#include <vector>

#include "ir/ir.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/solve/residual_correlation.hpp"

namespace sidc {

// Residual whiteness and input cross-correlation, one per equation group (in FitSummary order).
struct ResidualAnalysis {
  std::vector<ResidualCorrelationSummary> groups;
  std::vector<std::string> notes;  // per group: why it was not computed ("" when it was)
  std::vector<bool> truncated;     // per group: only the first kMaxResidualRows rows were used
  // Per group: the widest ratio of a Newey-West to a classical standard error (NaN where the fit has
  // none), and whether the Newey-West intervals are the ones to trust (trust_newey_west).
  std::vector<double> hac_widening;
  std::vector<bool> trust_newey_west;
};

// The residuals of a long record are read as far as this many rows: the band is then +-0.0026,
// finer than any decision needs, and a streamed fit's second pass stays short.
inline constexpr std::size_t kMaxResidualRows = 1'000'000;

// The residuals come from runtime/solve/residual_correlation.hpp's group_residuals: the fit's own for a
// dense fit, a second pass over row blocks for a streamed one.
ResidualAnalysis analyse_residuals(const ir::Model& model, const FitSummary& summary, const std::vector<SampledRecord>& records,
                                   const FitOptions& options);

}  // namespace sidc
