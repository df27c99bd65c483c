// `fit`: the parameters of a compiled model from sampled records, by weighted least squares
// (thesis section 2-1), solved by QR (runtime/solve/least_squares.hpp).
//
// Relies on: a compiled model and its records bound to signals (bind_record.hpp). Guarantees:
// equations that share no parameter are solved separately, equations that share parameters
// jointly (one design matrix, rows stacked); each record contributes its own rows from its own fit
// window, and, when there are several records, its own integration constants (named `C1@2` for
// record 2). The design (its columns, rows and weights) comes from design.hpp, every operation
// evaluated on the window; the summary carries the least-squares statistics of each group, each
// column's model parameter beside its name, and a report in the shape of the thesis' tables.
// Small groups are solved dense (the whole design, refinement against the rows, per-row
// residuals); large ones are streamed (FitOptions::stream_above_entries): row blocks evaluated by
// block_evaluator.hpp and folded into triangular_accumulator.hpp's factor on every core, in memory
// that does not grow with n, agreeing with the dense path to rounding
// (tests/runtime/streamed_fit_test.cpp). Row weights (eq. 2-1.6) come from a record column, from
// the model's `set weights = <expression>` (its value checked finite and >= 0 on every row), or
// from both (their product).
#pragma once

#include <functional>
#include <optional>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "ir/ir.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/operators/operator_choice.hpp"
#include "runtime/operators/test_functions.hpp"
#include "runtime/solve/design.hpp"
#include "runtime/solve/drift_check.hpp"
#include "runtime/solve/hac_covariance.hpp"
#include "runtime/solve/least_squares.hpp"
#include "runtime/solve/row_share.hpp"
#include "runtime/solve/weak_covariance.hpp"

namespace sidc {

struct FitSummary;

struct FitOptions {
  EvaluationOptions evaluation;
  LeastSquaresOptions least_squares;
  std::optional<double> from, to;  // fit window in time, for every record

  // Dense or streamed. A group whose design has at most this many entries (rows x columns; the
  // default is 64 MB of doubles) is solved dense: the whole design in memory, QR with refinement
  // against the original rows, per-row residuals in the summary. A larger one is streamed: its
  // rows are evaluated block by block (runtime/operators/block_evaluator.hpp) and folded into a triangular
  // factor (runtime/solve/triangular_accumulator.hpp), in memory that does not grow with n; refinement
  // then works on the triangle and the per-row vectors stay empty (for_each_residual_block gives
  // the residuals in a second pass). 0 streams every group.
  std::size_t stream_above_entries = 8'000'000;
  std::size_t stream_block_rows = 2048;  // rows evaluated and folded at a time
  int stream_threads = 0;                // threads folding row blocks; 0 = one per core, at most 8
  // Integrals from t0 are carried from stretch to stretch of this many rows (at least 4), so a
  // streamed integrated form holds one stretch of each integral (runtime/operators/running_integrals.hpp).
  std::size_t stream_stretch_rows = std::size_t{1} << 17;
  // Optional: a streamed group's rows folded so far and in all (per equation and record), after
  // each stretch, from the calling thread (a progress line; nothing computed depends on it).
  std::function<void(std::size_t done, std::size_t total)> progress;
  // The weak form's rows weighted by the covariance their noise gives them (weak_covariance.hpp;
  // `set weak_weighting = covariance`, the default); false: least squares of independent rows.
  // Optional, not owned: the processes a streamed group's rows are shared among (row_share.hpp; the
  // command line under mpirun, distributed/). Every process runs the same fit; a dense group is
  // fitted whole by each, and so is a group with more than 16 guards (2^guards region counts).
  RowShare* share = nullptr;
  bool weak_covariance = true;
  std::string weak_covariance_off = "set weak_weighting = none";  // why not, for the report, when false
  // Optional, not owned: a fit of the same model to records of the same shape whose data-driven
  // choices (noise levels and arcs per record, weak subdomains per group) this fit takes instead of
  // making its own, so that it differs from that one by the data alone (noise_check.hpp).
  const FitSummary* same_choices_as = nullptr;
  bool is_valid(std::string* why) const;
};

// The threads a streamed pass uses: FitOptions::stream_threads, or one per core (at most 8).
int stream_thread_count(const FitOptions& options);

// The rows one record gave to one group.
struct RecordRows {
  std::string path;
  double t0 = 0, t_last = 0, step = 0;
  std::size_t first_sample = 0, rows = 0;  // rows per equation
};

// Rows of the fit by the combination of guards that hold on them (the thesis' quadrants of the
// phase plane, Table 4-1.1, for eq. 4-1.8's four regions).
struct Region {
  std::string guards;  // e.g. "[y <= 0] and [y' >= 0]"; "(no guard)" when none holds
  std::size_t rows = 0;
};

struct GroupFit {
  std::vector<std::size_t> equations;          // indices into the model's equations
  std::vector<std::string> columns;            // parameter names, integration constants per record
  std::vector<ParameterIndex> column_parameters;  // beside columns: the model parameter (and record) of each
  std::vector<RecordRows> records;
  std::vector<Region> regions;  // empty when the equations have no guard
  bool weighted = false;        // rows weighted (eq. 2-1.6) by a record column and/or by the model's
                                // `set weights = <expression>` (both given: their product)
  LeastSquaresSummary summary;
  // Per row of the design: which equation and record, and at what time (for residual files).
  std::vector<std::size_t> row_equation, row_record;
  std::vector<double> row_time;
  std::vector<double> known;  // the right-hand side per row
  std::vector<DriftFinding> drift;  // integrated equations dominated by drift (drift_check.hpp; dense fits only)
  // Intervals honest under autocorrelated rows (hac_covariance.hpp): dense fits of dynamic models in
  // the derivative and integrated forms; `note` says why not for the others.
  HacEstimate hac;
  // Empty for a dense fit; for a streamed one, how (printed in the report), e.g. "streamed QR over
  // 9999988 rows in blocks of 2048 rows on 2 threads", and the per-row vectors above are empty.
  std::string streamed;
  // Weak-form groups (weak_design.hpp): per record, its subdomains and how their width was chosen.
  std::vector<std::string> subdomains;
  std::vector<TestFunctionGrid> weak_grids;  // the same, per record, as chosen
  WeakWeighting weak_weighting;  // weak-form groups: how their rows were weighted
  // CPU seconds (all threads) spent evaluating operations and folding rows (streamed fits), and
  // wall seconds of the final p x p solve, for the bench.
  double evaluate_seconds = 0, fold_seconds = 0, solve_seconds = 0;
};

struct FitSummary {
  std::string model_name;
  std::vector<GroupFit> groups;
  // Per record: every signal's noise level and, under savgol(auto), the arc chosen for each
  // derivative (operator_choice.hpp), with their warnings.
  std::vector<OperatorReport> operators;
  bool is_solution_usable() const;
  std::string brief_report() const;
  std::string full_report(const ir::Model& model) const;
};

std::variant<FitSummary, Diagnostic> fit(const ir::Model& model, const std::vector<SampledRecord>& records,
                                         const FitOptions& options);

// The first rows of a group's runs of neighbouring rows (one record's rows of one equation, from
// row_record and row_equation): where a lag of the Newey-West intervals must stop.
std::vector<std::size_t> neighbour_runs(const GroupFit& g);

// A warning per group whose statistics are not finite or not representable in a double
// (least_squares.hpp: unrepresentable_statistics), at its first equation.
std::vector<Diagnostic> statistics_warnings(const ir::Model& model, const FitSummary& summary);

// One row of a group's residuals: r_i = b_i - A_i x, unweighted (eq. 2-1.7 before weighting).
struct ResidualRow {
  std::size_t equation = 0, record = 0;  // indices into the model's equations and the records
  double time = 0, known = 0, residual = 0;
};

// The residual rows of group `group` of `summary` (a fit of `model` to `records` with `options`),
// in the design's row order (record by record, equation by equation, time increasing), handed to
// `rows` a block at a time: from the summary's per-row vectors for a dense fit, by evaluating the
// rows again block by block for a streamed one (memory independent of n).
std::optional<Diagnostic> for_each_residual_block(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                  const FitOptions& options, const FitSummary& summary, std::size_t group,
                                                  const std::function<bool(std::span<const ResidualRow>)>& rows,
                                                  std::size_t max_rows = static_cast<std::size_t>(-1));

// Equations grouped so that two equations sharing a parameter are in one group (in order).
std::vector<std::vector<std::size_t>> equation_groups(const ir::Model& model);

}  // namespace sidc
