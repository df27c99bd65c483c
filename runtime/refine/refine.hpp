// Output-error refinement (`sidc fit --refine`, `set refine = simulation`): the parameters that
// make the *solved* equations reproduce the record, not the evaluated operations. The thesis'
// equation-error fit (section 2-1) regresses on operations of the noisy record, so its regressors
// carry the noise and its estimates are biased (errors in variables); the output error of a
// simulation has the noise only in the record it is compared with, and its minimiser is the
// maximum-likelihood estimate under white measurement noise (MATLAB's nlgreyest, output-error
// models; Ljung, System Identification, 2nd ed., section 7.3).
//
// Relies on: runtime/simulate/simulate.hpp (the free run and its sensitivities: the variational
// equations, Jacobians derived symbolically), runtime/simulate/validate.hpp (a record made ready
// to simulate, the initial-state estimate), Ceres Solver (Levenberg-Marquardt, dense QR).
// Guarantees: minimises sum over records, outputs j and samples i of ((y_j(t_i) - yhat_j(t_i)) /
// s_j)^2 over the model's parameters and the initial state of every record (several records: one
// initial state each), starting from the equation-error estimate; s_j is output j's noise level
// (runtime/operators/noise_level.hpp) so outputs of different size and noise weigh by their
// likelihood. The Jacobian is exact for the RK4 run (sensitivities, not differences, with their
// jump at each located switch of a guard or sign()). A trial parameter set whose run diverges or becomes singular is a
// rejected step; a start that cannot be simulated, or a refinement that ends worse than it began,
// keeps the equation-error estimate and says so (status and a sentence), never silently. The
// covariance is Gauss-Newton's, sigma^2 (J^T J)^-1 with sigma^2 from the final residuals: honest
// when the output error is white, which the record's measurement noise is and the equation
// error's residuals are not.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "ir/explicit_form.hpp"
#include "ir/ir.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/records/sampled_record.hpp"

namespace sidc {

struct RefineOptions {
  int max_iterations = 100;
  // Ceres' convergence tests: relative change of the cost, of the parameters, and the gradient.
  double function_tolerance = 1e-12, parameter_tolerance = 1e-10, gradient_tolerance = 1e-12;
  // RK4 steps per sample interval; 0: chosen from the data (the fewest of 1, 2, 4, 8 whose run
  // agrees with twice as many steps to a hundredth of the noise).
  int substeps = 0;
  std::size_t max_samples = 0;   // per record, from the validation's start (0 = all)
  std::optional<double> from, to;  // the fit window (FitOptions): only its samples are compared
  EvaluationOptions evaluation;  // the fit's, for the moving-arc initial state
  // Multiple shooting: each record's run cut into this many segments (at most one per 20 samples),
  // each with its own initial state, joined by weighted continuity of the whole state (Bock's method
  // as a penalty). 1: single shooting. 0: chosen from the data: single, unless the
  // equation-error estimate's equations, solved from a record's start, diverge before its end; then
  // segments of half the span they lasted (at least 20 samples), so that each can be solved and the
  // refinement can start.
  int segments = 0;
};

struct RefinedParameter {
  std::string name;
  double linear = 0;          // the equation-error estimate the refinement started from
  double refined = 0;         // the output-error estimate (the linear one when the refinement failed)
  double standard_error = 0;  // Gauss-Newton; NaN when J^T J is singular
  std::string unit;           // as the fit table prints it; "" when the model gives none
  bool nonlinear = false;     // `linear` is the value the equation-error fit held it at (it enters nonlinearly)
};

struct RefinedRecord {
  std::string path;
  std::size_t samples = 0, first_sample = 0;  // compared, and the record's sample the run starts at
  std::size_t segments = 1;                    // shooting segments (multiple shooting when above 1)
  std::vector<std::pair<std::string, double>> initial_state;  // ("y'", value), refined
  std::map<std::string, std::vector<double>> initial;         // the same, as SimulateOptions::initial
  std::vector<std::pair<std::string, double>> rms_before, rms_after;  // per output, unweighted
};

struct RefineSummary {
  enum class Status { converged, stopped, failed };
  Status status = Status::failed;
  std::string message;  // one plain sentence: how it ended, or why the linear estimate was kept
  int iterations = 0;
  std::size_t residuals = 0;     // samples x outputs over every record
  std::size_t unknowns = 0;      // parameters plus initial-state components
  double cost_before = 0, cost_after = 0;  // 1/2 of the weighted sum of squares
  std::vector<RefinedParameter> parameters;  // in the normalized model's order
  std::vector<double> values;                // refined values, as SimulateOptions::parameters
  std::vector<RefinedRecord> records;
  std::vector<std::pair<std::string, double>> output_noise;  // s_j: the weights' scale per output
  std::vector<int> substeps;                                  // RK4 steps per sample interval, per record
  std::string shooting_reason;   // why segments were chosen (automatic multiple shooting), "" otherwise
  double largest_defect = 0;     // multiple shooting: the largest state jump left at a join, in noise units
  // The whiteness test of each output's error (runtime/solve/residual_correlation.hpp, over the
  // records): the intervals assume it white; `whiteness` has each output's one-line verdict.
  bool output_error_white = true;
  std::vector<std::pair<std::string, std::string>> whiteness;
  double seconds = 0;
  bool improved() const { return status != Status::failed; }
  std::string report() const;
};
const char* to_string(RefineSummary::Status status);

// `linear`: the equation-error estimate, by the normalized model's parameter (fitted_values.hpp).
// A Diagnostic only for what is wrong with the model or a record (an output not recorded, a term
// without a value at a point); numerical trouble is the summary's status.
std::variant<RefineSummary, Diagnostic> refine(const ir::Model& normalized, const ExplicitForm& form, const std::vector<double>& linear,
                                               const std::vector<const SampledRecord*>& records, const RefineOptions& options);

}  // namespace sidc
