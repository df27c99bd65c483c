// Validation of a fitted model by simulation, thesis section 2-4: "the most critical test of the
// validity of the derived model is obtained by solving the system equation using the parameters
// ... established by the least squares solution", compared with the record (section 4-1: max
// E[y] = 0.03, %E[y] = 1.5% for the odd-order model at Delta = 0.020).
//
// Relies on: runtime/simulate/simulate.hpp, runtime/simulate/initial_state.hpp, the explicit form of
// the *normalized* (derivative-form) model, so an integrated fit is validated through the equation
// it integrated; integration constants are not needed. Guarantees: the model is solved from the
// first sample where every state derivative has its centred moving-arc estimate (t = 3 Delta for
// y' by the 7-point operator; y itself by value) to the end of the record (or
// ValidationOptions::max_samples later), inputs taken from the record. The initial state is, by
// default, estimated by least squares over a start segment (start_segment_samples), starting from
// the recorded sample and its moving-arc derivatives; InitialState::record uses those as they are.
// Per output it gives the error curve E[y] = y_recorded - y_simulated (eq. 4-1.4), max |E| and its
// time, the thesis' percentage error 100 max|E| / max|y_recorded| (eq. 4-1.5: the error over the
// largest observed magnitude), MATLAB's fit percentage 100 (1 - ||y - yhat|| / ||y - mean(y)||),
// the RMS error, whether it follows (fit % >= kFollowsFitPercent) and where it departs. A run that
// diverges or becomes singular is not an error: the statement says so and when, and the numbers
// cover the samples before the stop.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "ir/explicit_form.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/simulate/simulate.hpp"

namespace sidc {

// The verdict's threshold: the fitted equations "follow" the record when, for every output, the
// simulated output's error is at most a tenth of the output's own variation about its mean (fit %
// = 100 (1 - ||y - yhat|| / ||y - mean(y)||) >= 90, MATLAB compare's measure). Below it the sentence
// says "do not follow it" and names the output, the fit %, where it departs (kDepartureShare) and
// its largest error. A noisy record lowers fit % by its noise: at a noise of 1% of the output's
// spread the cost is about 1 point, so the threshold separates a wrong model from a noisy record
// (once the start no longer comes from one noisy sample: InitialState::estimate).
inline constexpr double kFollowsFitPercent = 90;

// Where a run departs from the record: the first sample where the local RMS error (over the
// kDepartureHalfWidth samples either side, so one noisy sample does not count) exceeds
// kDepartureShare of the output's standard deviation about its mean: the share fit % allows over
// the whole record (fit % = 90 is an RMS error of 0.1 standard deviations), applied locally.
inline constexpr double kDepartureShare = 0.1;
inline constexpr std::size_t kDepartureHalfWidth = 5;

// Where the simulation's initial state comes from.
enum class InitialState {
  record,    // the sample at the start and its moving-arc derivatives (noisy on a noisy record)
  estimate,  // least squares over the start segment, from the recorded guess (MATLAB compare's estimate)
};
const char* to_string(InitialState initial);

// The start segment over which the initial state is estimated: a tenth of the samples compared,
// at least 20 (so that the noise averages out over more samples than there are states) and at
// most 1000 (each Levenberg-Marquardt iteration runs it once per state component). A fixed share
// rather than the system's time scales, which are what is being validated.
std::size_t start_segment_samples(std::size_t compared);

struct ValidationOptions {
  SimulateOptions::Method method = SimulateOptions::Method::rk4;
  int substeps = 4;           // rk4, the thesis' solver: four steps per sample interval
  double tolerance = 1e-9;    // adaptive
  // The free run's method from the model instead (free_run_method()); the initial-state estimate
  // keeps `method` (RK4 by default: its forward differences need a run smooth in the start, which
  // an adaptive stepper's step choices are not).
  bool choose_method = false;
  EvaluationOptions evaluation;  // the fit's, for the initial derivatives (edges are always shortened)
  // Samples compared at most, from the start (0 = all). A free run costs about 2 us per equation
  // evaluation, 16 per sample: 10^7 samples would take minutes, so sidc fit bounds it.
  std::size_t max_samples = 0;
  InitialState initial_state = InitialState::estimate;
  // Start at the record's first sample rather than at the first with a centred moving-arc estimate
  // of every state derivative (the initial guess there comes from off-centre arcs): for a run whose
  // outputs are needed at every sample (the instruments of runtime/solve/instrumental_variables.hpp).
  bool from_first_sample = false;
  // Optional: the free run's progress (SimulateOptions::progress), with the record's path.
  std::function<void(const std::string& record, std::size_t done, std::size_t total)> progress;
  // When the free run departs: test whether the equations are that sensitive to their initial
  // state, and if so judge them by runs restarted from the record within their horizon
  // (ValidationSummary::Restarted). sidc fit's validation; not the form choice or select, which
  // compare candidates by the free run alone.
  bool check_sensitivity = false;
};

// A chaotic or unstable system's solution cannot follow a record for long from any initial state
// known only to within its noise: two solutions started within that uncertainty separate as fast.
// So when the free run departs, it is run again from the estimated initial state displaced along
// each axis of its one-standard-deviation ellipsoid (InitialStateEstimate::uncertainty_axes); if a
// displaced run separates from the free run (by the departure test) no later than twice the time
// the record took to depart, the departure is what the equations' own sensitivity explains, and
// the verdict is taken instead from runs restarted from the record every half of that horizon
// (each from a state estimated over its own start segment), provided they span at least
// kRestartPeriods periods of the output that varies fastest: shorter runs would let a wrong model
// pass. A stable system contracts the displacement, so a model that departs there is judged by the
// free run as before.
inline constexpr double kRestartPeriods = 2;
// Each restarted run is compared with the record up to where its own displaced runs separate from
// it (the horizon depends on where in its orbit a chaotic solution starts); the verdict is judged
// only when the comparison covers at least this share of the record.
inline constexpr double kRestartComparedShare = 0.5;
// A long record with a short horizon is judged by at most this many restarted runs, evenly spread.
inline constexpr std::size_t kMostRestartedRuns = 200;
inline constexpr std::size_t kShortestRestart = 20;  // samples in each restarted run, at least

// The solver of a validation's free run: the adaptive stepper (Odeint's dopri5 with dense output
// at the samples, tolerance 1e-9), whose steps span as many sample intervals as the solution
// allows: a finely sampled record (thousands of samples per period) is not stepped four times per
// sample, which made the whole-record validation of 10^7 samples take over a minute. RK4 at four
// steps per sample instead when the equations have guard or sign() switches (RK4 locates each and
// steps to it exactly; the adaptive controller only shrinks its steps there) or a recorded input
// declared held or linear (every sample is then a jump or a kink that RK4 steps to).
SimulateOptions::Method free_run_method(const ir::Model& normalized, const ExplicitForm& form);
// How free_run_method()'s choice is named in the report: "RK4, 4 steps per sample interval" or
// "dopri5 (adaptive steps, tolerance 1e-09, dense output at the samples)".
std::string free_run_description(SimulateOptions::Method method, const ValidationOptions& options);

struct OutputValidation {
  std::string output;
  std::size_t samples = 0;        // compared (all, or those before a stop)
  double max_abs_error = 0;       // max |E| (eq. 4-1.4)
  double time_of_max = 0;
  double percent_error = 0;       // eq. 4-1.5
  double fit_percent = 0;         // 100 (1 - ||y - yhat|| / ||y - mean(y)||)
  double rms_error = 0;
  double mean = 0;                // the recorded output's mean and standard deviation about it (samples compared)
  double spread = 0;
  bool follows = false;               // fit % >= kFollowsFitPercent and the run completed
  std::optional<double> departs_at;   // see kDepartureShare; the stop when it stopped first; none when it never departs
};

struct ValidationSummary {
  std::string record;
  SimulationSummary simulation;
  std::vector<std::pair<std::string, double>> initial_state;  // ("y'", value): the state the run started from
  std::vector<std::pair<std::string, double>> recorded_state;  // the same read from the record (moving arc)
  InitialState initial_method = InitialState::record;
  std::size_t start_segment = 0;     // samples the estimate fitted (estimate only)
  int estimate_iterations = 0;       // Levenberg-Marquardt steps taken
  bool follows = false;              // every output follows
  std::vector<OutputValidation> outputs;
  // Per output, on simulation.time: the record (the solution is simulation.outputs, the error
  // E = recorded - simulated, eq. 4-1.4, not held: 8 bytes a sample less).
  std::vector<Column> recorded;  // borrowed from the record
  // The sensitivity test and the restarted runs (see kRestartPeriods): set when it was made.
  struct Restarted {
    double start = 0;                // t of the free run's first sample
    double free_run_departs_at = 0;  // the first departure of an output that does not follow
    std::optional<double> separates_at;  // where the first displaced run departs from the free run; none when none does
    bool start_unfitted = false;     // the free run departs within its own start segment
    bool sensitive = false;          // separates_at - t0 <= 2 (free_run_departs_at - t0), or start_unfitted
    double period = 0;               // of the fastest output (twice the duration over its turning points)
    bool judged = false;             // sensitive, and the restarted runs long enough and compared enough to judge by
    std::size_t runs = 0;
    double compared_share = 0;       // of the runs' samples, compared before each run's own displaced runs separate
    double run_duration = 0;         // of each run but perhaps the last (time units)
    double run_every = 0;            // between run starts: run_duration, or a multiple on a record too long for kMostRestartedRuns
    std::vector<std::pair<std::string, double>> fit_percent;  // per output, over every restarted run
    bool completed = true;           // every restarted run reached its end
    bool follows = false;            // judged, completed and every output at kFollowsFitPercent or more
    // The verdict's sentence, given the free run's shortfall as validate() words it.
    std::string statement(const std::string& free_run, double step) const;  // step: the record's, for printing times
  };
  std::optional<Restarted> restarted;
  std::string statement;  // one plain sentence: how well, or where it diverged
  bool truncated = false;  // ValidationOptions::max_samples stopped it before the record's end
  std::string report(const std::string& method) const;
};

// The state as printed: ("y", value), ("y'", value), ... in the explicit form's state order.
std::vector<std::pair<std::string, double>> named_state(const ExplicitForm& form, const std::map<std::string, std::vector<double>>& initial);

// A record made ready to be simulated (validate() and output-error refinement, runtime/refine/):
// the grid from the first sample where every state derivative has its centred moving-arc
// estimate (to ValidationOptions::max_samples), the record's inputs and initial values, the
// recorded outputs on that grid, and the moving-arc initial state in options.initial.
struct RecordRun {
  SimulateOptions options;                    // method and steps from the ValidationOptions; `parameters` set
  std::vector<Column> recorded;               // per output of the form, on options.time (borrowed from the record)
  std::size_t start = 0;                      // the record's sample at options.time[0]
  bool truncated = false;                     // max_samples stopped the grid before the record's end
  EvaluationOptions state_evaluation;         // the moving arcs of the initial state (at any sample)
};
// `record` must outlive the result (options.initial_value reads it).
std::variant<RecordRun, Diagnostic> record_run(const ir::Model& normalized, const ExplicitForm& form, const std::vector<double>& parameters,
                                               const SampledRecord& record, const ValidationOptions& options);

std::variant<ValidationSummary, Diagnostic> validate(const ir::Model& normalized, const ExplicitForm& form, const std::vector<double>& parameters,
                                                     const SampledRecord& record, const ValidationOptions& options);

// The validation of one `sidc fit` (thesis section 2-4): the fitted equations solved and compared
// with each record. Skipped, with one line saying why, when the equations cannot be solved for
// their highest derivatives or the fit is not usable; never an error of the fit itself, except for
// a record given only to be compared with (`failed_record`).
struct FitValidation {
  std::string note;  // why it was skipped; empty when it ran
  std::vector<ValidationSummary> runs;
  std::string method = "RK4, 4 steps per sample interval";
  std::size_t max_samples = 0;         // per record, 0 = all
  std::optional<Diagnostic> failed_record;  // a record past `fitted_records` that could not be compared
  std::string failed_path;                  // and its path
};

// `records`: the fitted records first (`fitted_records` of them), then those given only to be
// compared with; the runs borrow their columns (grids, recorded outputs), so they must outlive the result. `form`: the compiled model's explicit form of `normalized`. `refined`: the
// parameters (by the normalized model's parameter) to solve with instead of the fit's, and
// `refined_by` how they were had ("refined by the output error", "of instrumental variables").
// `check_sensitivity`: ValidationOptions::check_sensitivity (the form choice, which compares the
// candidates' free runs on pieces, leaves it out).
FitValidation validate_fit(const ir::Model& normalized, const std::variant<ExplicitForm, Diagnostic>& form, const FitSummary& summary,
                           const std::vector<const SampledRecord*>& records, std::size_t fitted_records, const EvaluationOptions& evaluation,
                           std::size_t max_samples, InitialState initial_state = InitialState::estimate,
                           const std::vector<double>* refined = nullptr, const std::string& refined_by = "refined by the output error",
                           const std::function<void(const std::string& record, std::size_t done, std::size_t total)>& progress = {},
                           bool check_sensitivity = true);

// Section 2-4's test as a selection criterion (`sidc select --simulate`): the derivative form solved
// with `values` for the parameters `subset` (the others 0; integration constants play no part) from each record (its initial
// state estimated as validate() does by default), scored by the RMS error over outputs and records; infinity when a run
// diverges, nullopt when a record cannot be compared.
std::optional<double> simulation_rms_error(const ir::Model& normalized, const ExplicitForm& form, const std::vector<ParameterIndex>& subset,
                                           const std::vector<double>& values, const std::vector<SampledRecord>& records,
                                           const EvaluationOptions& evaluation, std::size_t max_samples);

}  // namespace sidc
