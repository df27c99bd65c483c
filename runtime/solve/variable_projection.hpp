// The equation-error fit of a model with nonlinear parameters (`param L = 1.2` inside
// `sin(L*theta)`) by variable projection: for given values of the nonlinear parameters the linear
// ones follow by the thesis' least squares (eq. 2-1.8), so only the nonlinear ones are searched,
// each trial value costing one linear fit (Golub and Pereyra, SIAM J. Numer. Anal. 10(2), 1973).
//
// Relies on: ir/fix_parameters.hpp (the model with the nonlinear parameters held at values),
// runtime/solve/fit.hpp (the linear fit and its G, eq. 2-1.7). Guarantees: minimises the fit's
// total G over the nonlinear parameters, derivative-free (G of a rank-deficient or failed fit counts
// as infinite): first a scan of each parameter over factors 1/8 to 8 of its guess (a factor of
// sqrt(2) apart; from 0 a scan of +-1/8 to +-8), the best point kept, then Nelder-Mead from there
// until G changes by less than 1e-10 of itself or `max_fits` fits are spent. The values returned
// never have a larger G than the guesses (they are the guesses when nothing better was found).
// The G of an equation-error fit is biased under noise like its linear estimates; the values are
// the refinement's start (runtime/refine/), not its replacement.
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"
#include "runtime/records/sampled_record.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {

struct VariableProjectionOptions {
  int max_fits = 120;  // linear fits in all, the scan's included
};

struct VariableProjectionSummary {
  std::vector<std::string> names;       // the nonlinear parameters, in the model's order
  std::vector<double> guesses, values;  // theirs: as written, and where G is least
  double G_guess = 0, G_best = 0;       // total G (eq. 2-1.7) over the groups at each
  int fits = 0;
  // Per parameter of the model: `values` at the nonlinear ones, NaN at the others (as
  // fix_nonlinear takes them).
  std::vector<double> held;
  bool moved() const { return values != guesses; }
  std::string report() const;  // one paragraph
};

// `model` is the form to be fitted, its nonlinear parameters still in it. A Diagnostic only when
// the fit at the guesses fails for a reason in the model or the records (the same fit would fail).
std::variant<VariableProjectionSummary, Diagnostic> variable_projection(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                                        const FitOptions& options,
                                                                        const VariableProjectionOptions& projection = {});

}  // namespace sidc
