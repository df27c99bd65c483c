// The equation-error fit of a model with nonlinear parameters (`param L = 1.2` inside
// `sin(L*theta)`) by variable projection: for given values of the nonlinear parameters the linear
// ones follow by the thesis' least squares (eq. 2-1.8), so only the nonlinear ones are searched,
// each trial value costing one linear fit (Golub and Pereyra, SIAM J. Numer. Anal. 10(2), 1973).
//
// Relies on: ir/fix_parameters.hpp (the model with the nonlinear parameters held at values),
// runtime/solve/fit.hpp (the linear fit and its G, eq. 2-1.7). Guarantees: minimises the fit's
// total G over the nonlinear parameters, derivative-free (G of a rank-deficient or failed fit counts
// as infinite): first a scan of each parameter over factors 1/8 to 8 of its guess (a factor of
// sqrt(2) apart; from 0 a scan of +-1/8 to +-8), the best point kept, then Nelder-Mead from there,
// within the same range, until G changes by less than 1e-10 of itself, the simplex shrinks to 1e-9
// of the point, or `max_fits` fits are spent. A value that ends at the range's edge is named (the
// data may not determine it). The values returned
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
  std::vector<std::string> at_edge;  // those that ended at the edge of the range searched
  // From nonlinear_intervals (below), when the caller computed them: per nonlinear parameter, NaN
  // where there is none, and why not.
  std::vector<double> standard_errors;
  std::string interval_note;
  bool moved() const { return values != guesses; }
  std::string report() const;  // one paragraph
};

// `model` is the form to be fitted, its nonlinear parameters still in it. A Diagnostic only when
// the fit at the guesses fails for a reason in the model or the records (the same fit would fail).
std::variant<VariableProjectionSummary, Diagnostic> variable_projection(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                                        const FitOptions& options,
                                                                        const VariableProjectionOptions& projection = {});

// The equation-error intervals with the nonlinear parameters' own uncertainty in them. The fit at
// held values gives the linear parameters' intervals as if those values were known; the profile
// of G over the nonlinear parameters (the least G for each value, as variable projection searches
// it) has the curvature that gives theirs, Cov(k) = 2 s^2 (d^2 G/dk^2)^-1 with s^2 = G/(n - rank - m),
// and the linear solution moves with them by da/dk, which adds (da/dk) Cov(k) (da/dk)^T to the
// linear parameters' covariance: together, the Gauss-Newton covariance of all parameters at once.
// Both derivatives by central differences of whole fits (steps of 1e-3 of each value).
struct NonlinearIntervals {
  std::vector<double> standard_errors;  // per nonlinear parameter, in the model's order; NaN when none
  std::string note;                     // why there are none, "" when there are
};

// `model` has its nonlinear parameters (in the form fitted), `held` their values (per parameter of
// `model`, NaN for a linear one), `summary` the fit of fix_nonlinear(model, held): its
// standard errors, intervals and covariance are widened in place (the Newey-West ones are not).
NonlinearIntervals nonlinear_intervals(const ir::Model& model, const std::vector<SampledRecord>& records, const FitOptions& options,
                                       const std::vector<double>& held, FitSummary& summary);

}  // namespace sidc
