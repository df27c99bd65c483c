// Simulation: the model's equations solved forward in time with given parameter values (thesis
// section 2-4, "solving the system equation"; Appendix A was made this way with fourth-order
// Runge-Kutta, footnote to eq. 4-1.3).
//
// Relies on: compiler/explicit_form_pass.hpp (the equations solved for each output's highest
// derivative, parameters symbolic), runtime/operators/point_evaluator.hpp, Boost.Odeint (adaptive method).
// Guarantees: the state is (y, y', ..., y^(n-1)) per output; at each instant the k x k linear
// system of the highest derivatives is solved (k = 1: a division). Methods: classic fixed-step
// RK4 with `substeps` steps per output interval, guard and sign() switches located by bisection
// on the switching functions and stepped to exactly, each step taken in the branches it starts in
// (so a branch change never falls inside a step, not even in its last stage); or
// Odeint's dopri5 / cash_karp with absolute and relative tolerances (the adaptive controller
// shrinks its steps at a switch but does not locate it). Inputs bound to record columns are
// interpolated between samples by the 4-point cubic through the neighbouring samples (RK4 needs
// the input at half steps; linear interpolation would cap RK4's order at 2), unless declared
// `held` (the sample's value until the next sample) or `linear` (straight between samples): then
// no step crosses a sample instant (dopri5 becomes a controlled stepper taken sample by sample
// instead of dense output), a step ending at a sample sees the value its own interval has there,
// and a derivative of such an input is a Diagnostic. Inputs defined by an expression of t are
// evaluated exactly. Nothing aborts: a state that is not finite or
// exceeds `divergence_bound`, or a coefficient matrix of the highest derivatives that becomes
// singular or changes the sign of its determinant, stops the run with a status, the time and a
// plain sentence; outputs after that time are NaN.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "ir/explicit_form.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/records/column.hpp"

namespace sidc {

struct SimulateOptions {
  enum class Method { rk4, adaptive };
  Method method = Method::rk4;
  int substeps = 1;  // rk4: steps per interval of the output grid
  enum class Stepper { dopri5, cash_karp };
  Stepper stepper = Stepper::dopri5;
  double absolute_tolerance = 1e-9, relative_tolerance = 1e-9;  // adaptive
  bool locate_switches = true;                                  // rk4: step to each guard switch
  double divergence_bound = 1e8;  // |state| beyond this (times its state_scale) is divergence
  // Each state component's size (the explicit form's state order, per output y, y', ...); empty: all
  // 1. The adaptive stepper solves for the state divided by it, so its absolute tolerance is relative
  // to each component's size: a record in micrometres (y ~ 1e-7) is solved as accurately as one of
  // order 1, where an absolute tolerance of 1e-9 would let the stepper take any step.
  std::vector<double> state_scale;

  std::vector<double> parameters;  // by index into the normalized model's parameters
  // Initial state per output: y(t0), y'(t0), ..., y^(n-1)(t0) (n values, the output's order).
  std::map<std::string, std::vector<double>> initial;
  // The output grid, increasing, time[0] = t0; uniform not required. A Column, so that a record's
  // own samples are simulated against where they lie (a copy is 80 MB at 10^7 samples).
  Column time;
  // Inputs without a definition: samples on `time` (a record's columns, borrowed the same way).
  std::map<std::string, Column> inputs;
  double t0_for_tau = 0;  // the window start `t0` (and tau = t - t0) as the model means it; usually time[0]
  // The value of an initial-value factor such as `y2(0)` (eq. 4-2.4's constants=initial form);
  // unset, or nullopt from it: the model cannot be simulated (a Diagnostic at the term).
  std::function<std::optional<double>(const ir::Factor&)> initial_value;

  // Also integrate the sensitivities d y / d q of every output to every parameter of the normalized
  // model and every initial-state component (the variational equations, with Jacobians derived
  // symbolically by ir/differentiate.hpp): the exact Jacobian output-error refinement needs
  // (runtime/refine/refine.hpp). Under RK4 they are the exact derivatives of the discrete run, with
  // the jump each located switch of a guard or sign() adds (the switch time moves with q).
  bool sensitivities = false;

  // Optional: told the output rows done and in all, every 65,536 rows and at the end of a
  // completed run (a progress line for long runs; nothing computed depends on it).
  std::function<void(std::size_t done, std::size_t total)> progress;

  bool is_valid(std::string* why) const;
  // These options with the grid and the input samples cut to their first `n` (a start segment of a
  // long record: copying 10^7 samples to keep 1000 costs more than the segment's run). Every other
  // setting as it is: a field added above must be added to this copy too.
  SimulateOptions first_samples(std::size_t n) const;
  // The same for grid samples [first, last): a segment of a record (multiple shooting). The inputs'
  // interpolation then sees the segment's samples only.
  SimulateOptions samples(std::size_t first, std::size_t last) const;
};

struct SimulationSummary {
  enum class Status { completed, diverged, singular };
  Status status = Status::completed;
  std::string message;                 // one plain sentence; empty when completed
  std::optional<double> stopped_at;    // when it diverged or became singular
  std::size_t steps = 0;               // accepted steps (rk4: including partial steps at switches)
  std::size_t switches = 0;            // guard switches located (rk4)
  std::size_t right_hand_sides = 0;    // evaluations of the equations
  Column time;  // the options' grid: shared with them when they borrow a record's samples
  std::vector<std::string> output_names;
  std::vector<std::vector<double>> outputs;  // per output, on `time`; NaN after stopped_at
  // With SimulateOptions::sensitivities: per output, row-major [row * sensitivity_columns + q], d y / d q
  // for q = the parameters (in the normalized model's order), then the initial state (per output
  // y, y', ..., in the order of the explicit form's outputs).
  std::vector<std::vector<double>> sensitivity;
  std::size_t sensitivity_columns = 0;
  // At the last grid time of a completed run: the state (explicit form's order, state_size() values)
  // and, with sensitivities, d state / d q column by column (q as in `sensitivity`), state_size()
  // values per column. Multiple shooting joins segments by it. Empty when the run stopped early.
  std::vector<double> final_vector;
  bool completed() const { return status == Status::completed; }
  std::string brief_report() const;
};

// The initial state as a vector in the explicit form's state order (per output, y, y', ...,
// y^(n-1): the order of the state and of the initial-state sensitivity columns), a component
// `initial` lacks as 0; and the vector back as SimulateOptions::initial.
std::vector<double> state_vector(const ExplicitForm& form, const std::map<std::string, std::vector<double>>& initial);
std::map<std::string, std::vector<double>> state_map(const ExplicitForm& form, std::span<const double> x);

// Compiles the explicit form for point evaluation and runs the simulation. Diagnostics are for
// the model (an input with no values, a term that has no value at a point); numerical trouble is
// a status in the summary.
std::variant<SimulationSummary, Diagnostic> simulate(const ir::Model& normalized, const ExplicitForm& form, const SimulateOptions& options);
// The same into `summary`, whose arrays are reused (a refinement runs one record many times).
std::optional<Diagnostic> simulate_into(const ir::Model& normalized, const ExplicitForm& form, const SimulateOptions& options,
                                        SimulationSummary& summary);

// y(t), y'(t), ..., y^(n-1)(t) of each output at sample `index` of a record, derivatives by the
// moving arc with off-centre (shortened) windows at the edges, so the first sample has them;
// under savgol(auto) the arc chosen for each output and order from this record, as fit chooses it
// (`arcs_chosen`: `evaluation` is already state_operators_for_record's result for this record).
std::variant<std::map<std::string, std::vector<double>>, Diagnostic> initial_state_from_record(const ExplicitForm& form,
                                                                                              const SampledRecord& record,
                                                                                              const EvaluationOptions& evaluation,
                                                                                              std::size_t index, bool arcs_chosen = false);

// `evaluation` with the arcs of the outputs' derivatives below their orders chosen for `record`
// (operator_choice.hpp; unchanged without savgol(auto)).
std::variant<EvaluationOptions, Diagnostic> state_operators_for_record(const ExplicitForm& form, const SampledRecord& record,
                                                                       const EvaluationOptions& evaluation);

}  // namespace sidc
