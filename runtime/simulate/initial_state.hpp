// The initial state of a validation run estimated from the record, like MATLAB compare's estimated
// initial condition: one noisy sample and its moving-arc derivatives make a poor start (a y' off
// by its noise sets a lightly damped system oscillating for the whole record), so the start that
// best reproduces the record over a start segment is used instead.
//
// Relies on: runtime/simulate/simulate.hpp (the free run) and Eigen. Guarantees: minimises
// sum_j sum_i ((y_j(t_i) - yhat_j(t_i; x0)) / s_j)^2 over the first `segment` samples of the
// grid, over the initial state x0 = (y, y', ..., y^(n-1)) of every output only (the parameters
// stay fixed), by Levenberg-Marquardt started from `options.initial` (the moving-arc estimate),
// with forward-difference sensitivities (one extra run of the segment per state component); s_j
// is output j's standard deviation over the segment (1 when it is constant), so outputs of
// different size weigh alike. A trial start whose run diverges or becomes singular counts as
// infinitely bad, so the result never reproduces the segment worse than the starting guess.
// Deterministic; at most kMaxIterations iterations. How far the start is known comes from the last
// Jacobian J: Gauss-Newton's covariance sigma^2 (J^T J)^-1 for residuals of standard deviation
// sigma (in units of s_j), given by the axes of its ellipsoid, sigma v_k / s_k for J's singular
// values s_k and right singular vectors v_k: each a displacement of the start that fits the
// segment worse by sigma. Axes, not per-component standard errors: on a chaotic record the start is
// known to a hair along the directions the solution amplifies and loosely along those it damps,
// and the components' errors mix the two (validation's sensitivity test displaces the start along
// each axis, with sigma the record's noise level rather than the misfit, so that a wrong model
// does not widen its own uncertainty).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "ir/explicit_form.hpp"
#include "runtime/simulate/simulate.hpp"

namespace sidc {

struct InitialStateEstimate {
  std::map<std::string, std::vector<double>> initial;  // per output, as SimulateOptions::initial
  std::size_t segment = 0;                              // samples compared
  int iterations = 0;                                   // accepted Levenberg-Marquardt steps
  double cost_before = 0, cost_after = 0;               // the sum of squares above, at the guess and at the estimate
  // The uncertainty ellipsoid's axes for sigma = 1, each a displacement of the state (the explicit
  // form's order); empty when no Jacobian was formed or one direction leaves the segment unchanged.
  std::vector<std::vector<double>> uncertainty_axes;
  std::vector<double> scales;  // s_j, per output
};

// `options`: the whole run (grid, inputs, parameters, initial guess in `initial`); `recorded`:
// per output of `form` the recorded values on options.time. Only the first `segment` samples
// (at least 2) are simulated.
InitialStateEstimate estimate_initial_state(const ir::Model& normalized, const ExplicitForm& form, const SimulateOptions& options,
                                            const std::vector<Column>& recorded, std::size_t segment);

}  // namespace sidc
