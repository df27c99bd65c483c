// The refined instrumental-variable estimate (`set estimator = iv`, `sidc fit --estimator iv`): the
// equation-error fit (fit.hpp) is biased under noise because its regressors, the operations
// evaluated on the noisy record, carry the noise (errors in variables). Instruments free of it are
// the same operations evaluated on the fitted equations' own noise-free solution: Young and
// Jakeman's refined instrumental variables for continuous-time models (SRIVC; P. C. Young and
// A. J. Jakeman, "Refined instrumental variable methods of recursive time-series analysis, part III:
// extensions", Int. J. Control 31, 1980), iterated from the equation-error estimate: solve the
// equations with the current estimate, build the instruments from the solution, solve the square
// IV system, repeat. sidc's integrated and weak forms already filter the record (integrals from
// t0, test functions), so they act as SRIVC's prefilter, applied alike to the record and the
// solution.
//
// Relies on: fit.hpp's summary of the equation-error fit (its per-record arcs and its groups),
// design.hpp and weak_design.hpp (the same rows, columns and weights for the record and for the
// instruments; the weak form's subdomains chosen once, from the record), runtime/simulate/validate.hpp
// (the solution from every record's first sample, its initial state estimated by least squares
// over a start segment). Guarantees: the regressors Phi and the known side b are the fit's own; the
// instruments Z are the design evaluated on a copy of each record whose outputs are the solution
// (inputs, weights and time kept), so a column that does not depend on the outputs (an integration
// constant, an input) is its own instrument; each iterate solves Z^T W Phi theta = Z^T W b by QR of
// the weighted, scaled instruments (see instrumental_variables.cpp), its covariance is
// sigma^2 (Z^T Phi)^-1 (Z^T Z) (Phi^T Z)^-1 with sigma^2 from the IV residuals b - Phi theta; the
// iteration stops when no parameter moves by more than `tolerance` of itself (or of its
// equation-error standard error, when that is larger) or after `max_iterations`. A solution that diverges, instruments that
// cannot be evaluated or are dependent stop it with a sentence saying so, and the last estimate whose
// equations could be solved is kept and named: never a silent fallback. Dense groups only (a streamed
// group is said to be out of reach).
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "ir/explicit_form.hpp"
#include "ir/ir.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {

struct InstrumentalVariablesOptions {
  int max_iterations = 10;  // IV solves at most; SRIVC usually settles in 3 to 6
  // The iteration has converged when, from one iterate to the next, no parameter moves by more
  // than this share of max(|value|, its equation-error standard error): relative to the value,
  // except for a parameter indistinguishable from zero, whose relative change would never settle.
  double tolerance = 1e-6;
  double confidence_level = 0.95;  // two-sided Student t intervals, n - p degrees of freedom
  bool is_valid(std::string* why) const;
};

struct InstrumentalVariablesParameter {
  std::string name;
  std::optional<ParameterIndex> index;
  double value = 0, standard_error = 0, ci_low = 0, ci_high = 0;
  double equation_error = 0;  // the equation-error (least-squares) estimate, for comparison
  // Newey-West (HAC) standard error and interval (hac_covariance.hpp), which allow for
  // autocorrelated rows; NaN where the group's `hac_note` says why not.
  double hac_standard_error = std::numeric_limits<double>::quiet_NaN(), hac_ci_low = hac_standard_error, hac_ci_high = hac_standard_error;
  std::string unit;           // as the fit table prints it; "" when the model gives none
};

struct InstrumentalVariablesGroup {
  std::string form;  // of its equations: "derivative", "integrated" or "weak" (the intervals' caveat differs)
  std::vector<InstrumentalVariablesParameter> parameters;  // in the fit's column order
  std::size_t n = 0, p = 0;     // rows with non-zero weight, columns
  double residual_sd = 0;       // sqrt(sum (w (b - Phi theta))^2 / (n - p))
  bool hac = false;             // the parameters' HAC intervals computed
  double hac_bandwidth = 0;
  double lag1 = 0, band = 0;    // the IV residuals' lag-1 autocorrelation, and its 99% band 2.576/sqrt(n)
  std::string hac_note;         // why not, when not
};

struct InstrumentalVariablesSummary {
  enum class Termination {
    converged,       // the last change was below the tolerance
    max_iterations,  // the last IV estimate is kept, its change above the tolerance
    stopped,         // a solution diverged, or instruments could not be evaluated or were dependent: the last good estimate kept
    not_started,     // nothing to iterate from (no explicit form, a rank-deficient or streamed fit, ...): the equation-error estimate stands
  };
  Termination termination = Termination::not_started;
  std::string statement;        // one plain sentence: what happened and which estimate is kept
  int iterations = 0;           // IV solves behind the kept estimate (0: it is the equation-error estimate)
  int max_iterations = 0;
  double tolerance = 0;
  std::vector<double> changes;  // per IV solve: the largest relative change (see the options)
  // The worst fit % (validate.hpp's measure, over outputs and records) of the equations solved
  // from the records: the equation-error estimate's, and the kept estimate's; none when not solved.
  std::optional<double> equation_error_fit_percent, fit_percent;
  std::vector<InstrumentalVariablesGroup> groups;  // the kept estimate, per group of the fit; empty when not started
  bool is_solution_usable() const;  // an IV estimate is kept (converged, or the last of max_iterations)
  std::string brief_report() const;
  std::string full_report() const;  // the section printed after the fit's own report
};

const char* to_string(InstrumentalVariablesSummary::Termination termination);

// The kept IV estimate by the parameters of `normalized` (the derivative form, whose parameters
// come first in the fitted model's order), `fallback`'s value where the IV summary has none.
std::vector<double> instrumental_parameter_values(const ir::Model& normalized, const InstrumentalVariablesSummary& iv,
                                                  std::vector<double> fallback);

// `model`: the fitted (integrated, weak or derivative) model; `normalized` and `form`: its
// derivative form and its explicit form (or why there is none), which are solved; `fitted`:
// fit(model, records, options). Never fails: invalid options and every numerical problem are a
// termination with its statement.
InstrumentalVariablesSummary instrumental_variables(const ir::Model& model, const ir::Model& normalized,
                                                    const std::variant<ExplicitForm, Diagnostic>& form,
                                                    const std::vector<SampledRecord>& records, const FitOptions& options,
                                                    const FitSummary& fitted, const InstrumentalVariablesOptions& iv_options = {});

}  // namespace sidc
