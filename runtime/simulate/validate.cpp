#include "runtime/simulate/validate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <fmt/format.h>

#include "diagnostics/time_text.hpp"
#include "runtime/operators/noise_level.hpp"
#include "runtime/simulate/initial_state.hpp"
#include "runtime/solve/fitted_values.hpp"

namespace sidc {

std::vector<std::pair<std::string, double>> named_state(const ExplicitForm& form, const std::map<std::string, std::vector<double>>& initial) {
  const std::vector<double> x = state_vector(form, initial);
  std::vector<std::pair<std::string, double>> named;
  std::size_t k = 0;
  for (const auto& out : form.outputs)
    for (int m = 0; m < out.order; ++m) named.emplace_back(out.name + std::string(static_cast<std::size_t>(m), '\''), x[k++]);
  return named;
}

namespace {

constexpr double kNotFinite = -1;  // a square's place when the error is not finite (squares are >= 0)

// The first time the local RMS of e = y - yhat (kDepartureHalfWidth samples either side, those that are
// finite) exceeds `limit`; none when it never does.
// Each square is taken once (a whole record has millions of samples, each in 11 windows), kept in
// a ring of the window's length, and the window's squares are added in sample order, as a sum
// over the window taken afresh would.
std::optional<double> departure(std::span<const double> y, std::span<const double> yhat, std::span<const double> time, double limit) {
  const std::size_t n = y.size(), w = kDepartureHalfWidth, length = 2 * w + 1;
  std::array<double, 2 * kDepartureHalfWidth + 1> ring;  // squares[k] at k % length; kNotFinite where e[k] is not finite
  auto square = [&](std::size_t k) {
    const double e = y[k] - yhat[k];
    return std::isfinite(e) ? e * e : kNotFinite;
  };
  // No window can exceed the limit when no square does by half: the mean of at most 11 squares,
  // however rounded, stays within a part in 10^15 of at most the largest. One pass settles the
  // common case (a run that follows the record) without the windows.
  double largest = 0;
  for (std::size_t k = 0; k < n; ++k) largest = std::max(largest, square(k));
  if (std::isfinite(largest) && largest <= 0.5 * limit * limit) return std::nullopt;
  for (std::size_t k = 0; k < std::min(n, w + 1); ++k) ring[k % length] = square(k);
  for (std::size_t i = 0; i < n; ++i) {
    if (i + w < n && i > 0) ring[(i + w) % length] = square(i + w);  // the window's new right end
    double sum = 0;
    std::size_t count = 0;
    for (std::size_t k = i > w ? i - w : 0; k <= std::min(n - 1, i + w); ++k)
      if (const double s = ring[k % length]; s != kNotFinite) sum += s, ++count;
    if (count && std::sqrt(sum / static_cast<double>(count)) > limit) return time[i];
  }
  return std::nullopt;
}

// A sum of squares kept as scale^2 * sum (LAPACK's dnrm2 way): finite for values near 1e200.
struct ScaledSquares {
  double scale = 0, sum = 0;
  void add(double x) {
    const double a = std::abs(x);
    if (a == 0) return;
    if (a > scale) {
      sum = 1 + sum * (scale / a) * (scale / a);
      scale = a;
    } else {
      sum += (a / scale) * (a / scale);
    }
  }
  double norm() const { return scale * std::sqrt(sum); }
};

// The period of the output that varies fastest: for each, twice the record's duration over the
// number of its turning points, counted as a zig-zag does (a maximum or minimum counts once the
// output has moved away from it by `band`: a quarter of its standard deviation, and at least five
// times its noise level `noise`, so noise makes no turns). Turning points rather than crossings of the
// mean: an output that oscillates within one well of a double well (a chaotic Duffing
// oscillator) crosses its mean only when it changes wells. The record's duration for an output
// that never turns.
double fastest_period(const std::vector<Column>& recorded, const std::vector<double>& noise, std::span<const double> time) {
  const double duration = time.back() - time.front();
  double fastest = duration;
  for (std::size_t j = 0; j < recorded.size(); ++j) {
    const Column& y = recorded[j];
    const double band = std::max(0.25 * standard_deviation(y), 5 * noise[j]);
    if (!(band > 0) || !std::isfinite(band)) continue;
    int direction = 0;  // +1 rising from the last turn, -1 falling; 0 before the first swing
    double extreme = NAN, high = -INFINITY, low = INFINITY;
    std::size_t turns = 0;
    for (double v : y) {
      if (!std::isfinite(v)) continue;
      if (direction == 0) {
        high = std::max(high, v), low = std::min(low, v);
        if (v < high - band) direction = -1, extreme = v;
        else if (v > low + band) direction = 1, extreme = v;
      } else if (direction * (v - extreme) > 0) {
        extreme = v;
      } else if (direction * (extreme - v) > band) {
        ++turns, direction = -direction, extreme = v;
      }
    }
    if (turns > 0) fastest = std::min(fastest, 2 * duration / static_cast<double>(turns));
  }
  return fastest;
}

// The axes of `estimate`'s uncertainty for residuals of the record's noise level (`noise`, per
// output) rather than the misfit's, at least `floor` of each output's spread (the solver's
// tolerance, for a record without noise); empty when the estimate has none.
std::vector<std::vector<double>> uncertainty_axes(const InitialStateEstimate& estimate, const std::vector<double>& noise, double floor) {
  if (estimate.scales.size() != noise.size() || noise.empty()) return {};
  double squares = 0;
  for (std::size_t j = 0; j < noise.size(); ++j) squares += (noise[j] / estimate.scales[j]) * (noise[j] / estimate.scales[j]);
  const double sigma = std::max(std::sqrt(squares / static_cast<double>(noise.size())), floor);
  std::vector<std::vector<double>> axes = estimate.uncertainty_axes;
  for (auto& axis : axes)
    for (double& x : axis) x *= sigma;
  return axes;
}

// Where runs from `run`'s start displaced along each of `axes` first separate from `nominal` (its
// solution): the departure test with kDepartureShare of each output's `spreads`, or where a
// displaced run stops; infinity when none separates, nullopt when one cannot be run.
std::optional<double> separation(const ir::Model& normalized, const ExplicitForm& form, const SimulateOptions& run,
                                 const SimulationSummary& nominal, const std::vector<std::vector<double>>& axes,
                                 const std::vector<double>& spreads) {
  double separates = INFINITY;
  const std::vector<double> start = state_vector(form, run.initial);
  for (const auto& axis : axes) {
    SimulateOptions displaced = run;
    displaced.progress = {};
    std::vector<double> x = start;
    for (std::size_t k = 0; k < x.size(); ++k) x[k] += axis[k];
    displaced.initial = state_map(form, x);
    auto twin = simulate(normalized, form, displaced);
    if (!std::holds_alternative<SimulationSummary>(twin)) return std::nullopt;
    const SimulationSummary& other = std::get<SimulationSummary>(twin);
    if (!other.completed()) separates = std::min(separates, other.stopped_at.value_or(run.time.front()));
    for (std::size_t j = 0; j < form.outputs.size(); ++j)
      if (spreads[j] > 0)
        if (auto t = departure(nominal.outputs[j], other.outputs[j], run.time, kDepartureShare * spreads[j])) separates = std::min(separates, *t);
  }
  return separates;
}

// The sensitivity test and the restarted runs of ValidationSummary::Restarted, for a completed
// free run `v` of `prepared` (its options with the estimated start and the free-run method; its
// recorded outputs now in v.recorded) that departs at `departs_at`. nullopt when the test cannot
// be made (no uncertainty axes, a failed run).
std::optional<ValidationSummary::Restarted> restart_within_horizon(const ir::Model& normalized, const ExplicitForm& form,
                                                                   const SampledRecord& record, const RecordRun& prepared,
                                                                   const ValidationSummary& v, const std::vector<std::vector<double>>& axes,
                                                                   const std::vector<double>& noise, double departs_at,
                                                                   const ValidationOptions& options) {
  const SimulateOptions& free_run = prepared.options;
  const std::span<const double> time = free_run.time;
  const std::size_t n = time.size();
  if (axes.size() != form.state_size() || n < 2 * kShortestRestart) return std::nullopt;
  ValidationSummary::Restarted out;
  out.start = time.front();
  out.free_run_departs_at = departs_at;
  std::vector<double> spreads;
  for (const auto& r : v.outputs) spreads.push_back(r.spread);
  const std::optional<double> separates = separation(normalized, form, free_run, v.simulation, axes, spreads);
  if (!separates) return std::nullopt;
  if (!std::isfinite(*separates)) return out;  // the displacement stays small: a stable run, judged by itself
  out.separates_at = *separates;
  // A free run that departs within the segment its start was estimated over has a start that did
  // not fit even there (a chaotic record's start segment can outlast its horizon): the departure
  // says nothing of the equations, and the restarted runs judge them.
  out.start_unfitted = v.start_segment > 0 && departs_at < time[std::min(v.start_segment, n) - 1];
  out.sensitive = out.start_unfitted || *separates - time.front() <= 2 * (departs_at - time.front());
  out.period = fastest_period(v.recorded, noise, time);
  if (!out.sensitive) return out;

  // Runs of half the horizon, restarted from the record's state (moving arc, then estimated), each
  // compared with the record up to where its own displaced runs separate from it: the horizon
  // depends on where in its orbit a chaotic solution starts.
  const std::size_t horizon = static_cast<std::size_t>(std::lower_bound(time.begin(), time.end(), *separates) - time.begin());
  const std::size_t length = horizon / 2;
  if (length < kShortestRestart || length >= n || time[length] - time.front() < kRestartPeriods * out.period) return out;
  out.run_duration = time[length] - time.front();
  std::vector<ScaledSquares> errors(form.outputs.size()), deviations(form.outputs.size());
  // At most kMostRestartedRuns runs, evenly spread (every stride-th stretch of `length` samples),
  // so that a long record with a short horizon costs a bounded number of estimates and runs.
  const std::size_t stretches = n / length, stride = (stretches + kMostRestartedRuns - 1) / kMostRestartedRuns;
  out.run_every = static_cast<double>(stride) * out.run_duration;
  std::size_t compared = 0, covered = 0;
  for (std::size_t first = 0; first < n;) {
    // The last run takes what is left when less than half a run would remain.
    const std::size_t last = first + length + length / 2 > n ? n : first + length;
    covered += last - first;
    auto guess = initial_state_from_record(form, record, prepared.state_evaluation, prepared.start + first, true);
    if (!std::holds_alternative<std::map<std::string, std::vector<double>>>(guess)) return std::nullopt;
    SimulateOptions run = free_run.samples(first, last);
    run.progress = {};
    run.initial = std::get<std::map<std::string, std::vector<double>>>(std::move(guess));
    std::vector<Column> recorded;
    for (const Column& y : v.recorded)  // views of v.recorded, which outlives them (a handle that owns nothing)
      recorded.push_back(Column::borrowed(std::span<const double>(y).subspan(first, last - first),
                                          std::shared_ptr<const void>(std::shared_ptr<const void>{}, &v)));
    SimulateOptions estimate_with = run;
    estimate_with.method = options.method;  // as validate() estimates the free run's start
    const InitialStateEstimate estimate = estimate_initial_state(normalized, form, estimate_with, recorded, start_segment_samples(last - first));
    run.initial = estimate.initial;
    auto solved = simulate(normalized, form, run);
    if (!std::holds_alternative<SimulationSummary>(solved)) return std::nullopt;
    const SimulationSummary& s = std::get<SimulationSummary>(solved);
    out.completed = out.completed && s.completed();
    std::size_t until = last - first;  // compared samples of this run
    const std::vector<std::vector<double>> run_axes = uncertainty_axes(estimate, noise, options.tolerance);
    if (s.completed() && run_axes.size() == form.state_size()) {
      const std::optional<double> apart = separation(normalized, form, run, s, run_axes, spreads);
      if (!apart) return std::nullopt;
      until = static_cast<std::size_t>(std::lower_bound(run.time.begin(), run.time.end(), *apart) - run.time.begin());
    }
    compared += until;
    for (std::size_t j = 0; j < form.outputs.size(); ++j)
      for (std::size_t i = 0; i < until; ++i) {
        const double y = recorded[j][i], e = y - s.outputs[j][i];
        if (!std::isfinite(y)) continue;
        deviations[j].add(y - v.outputs[j].mean);
        if (std::isfinite(e)) errors[j].add(e);
      }
    ++out.runs;
    first = last == n ? n : first + stride * length;
  }
  out.compared_share = static_cast<double>(compared) / static_cast<double>(covered);
  // Runs cut short everywhere would be too weak a test, like runs too short to begin with.
  out.judged = out.compared_share >= kRestartComparedShare;
  if (!out.judged) return out;
  out.follows = out.completed;
  for (std::size_t j = 0; j < form.outputs.size(); ++j) {
    const double d = deviations[j].norm();
    const double fit = d > 0 ? 100 * (1 - errors[j].norm() / d) : (errors[j].norm() == 0 ? 100 : NAN);
    out.fit_percent.emplace_back(form.outputs[j].name, fit);
    out.follows = out.follows && fit >= kFollowsFitPercent;
  }
  return out;
}

}  // namespace

SimulateOptions::Method free_run_method(const ir::Model& normalized, const ExplicitForm& form) {
  if (!form.switching_functions.empty()) return SimulateOptions::Method::rk4;
  for (const auto& s : normalized.signals)
    if (s.kind == ir::Signal::Kind::input && !s.definition && s.hold != ir::Signal::Hold::smooth) return SimulateOptions::Method::rk4;
  return SimulateOptions::Method::adaptive;
}

std::string free_run_description(SimulateOptions::Method method, const ValidationOptions& options) {
  if (method == SimulateOptions::Method::adaptive)
    return fmt::format("dopri5 (adaptive steps, tolerance {:g}, dense output at the samples)", options.tolerance);
  return fmt::format("RK4, {} step{} per sample interval", options.substeps, options.substeps == 1 ? "" : "s");
}

const char* to_string(InitialState initial) { return initial == InitialState::record ? "record" : "estimate"; }

std::size_t start_segment_samples(std::size_t compared) {
  return std::min(compared, std::clamp<std::size_t>(compared / 10, 20, 1000));
}

std::variant<RecordRun, Diagnostic> record_run(const ir::Model& normalized, const ExplicitForm& form, const std::vector<double>& parameters,
                                               const SampledRecord& record, const ValidationOptions& options) {
  RecordRun run;
  SimulateOptions& o = run.options;
  o.method = options.method;
  o.substeps = options.substeps;
  o.absolute_tolerance = o.relative_tolerance = options.tolerance;
  o.parameters = parameters;
  // The first sample where every state derivative has its centred moving-arc estimate, as good
  // as the fit's own: an off-centre estimate at the very first sample can be far off on a rounded
  // record (Appendix A: y'(0) = -2.7 at Delta = 0.020 where the truth is 0).
  std::size_t start = 0;
  auto chosen = state_operators_for_record(form, record, options.evaluation);
  if (auto* d = std::get_if<Diagnostic>(&chosen)) return *d;
  for (const auto& out : form.outputs)
    for (int m = 1; m < out.order && !options.from_first_sample; ++m) {
      DerivativeOptions centred = derivative_options_for(std::get<EvaluationOptions>(chosen), out.name, m);
      centred.edges = DerivativeOptions::Edges::drop;
      start = std::max(start, static_cast<std::size_t>(std::max(0, samples_lost_each_side(m, centred))));
    }
  if (start + 1 >= record.time.size()) start = 0;
  const auto from = static_cast<std::ptrdiff_t>(start);
  const auto to = static_cast<std::ptrdiff_t>(options.max_samples > 0 ? std::min(record.time.size(), start + options.max_samples) : record.time.size());
  // The record's own samples, borrowed, not copied (80 MB a column at 10^7 samples): the record
  // outlives the run, as options.initial_value's reading of it already requires.
  const std::shared_ptr<const void> record_alive(std::shared_ptr<const void>{}, &record);
  const auto on_grid = [&](const Column& column) {
    return Column::borrowed(std::span<const double>(column).subspan(static_cast<std::size_t>(from), static_cast<std::size_t>(to - from)), record_alive);
  };
  o.time = on_grid(record.time);
  o.t0_for_tau = record.time.front();
  // `y(0)`, `y(t0)`, `y(2.5)`: a recorded output's value, as the fit read it (eq. 4-2.4). Derivatives
  // at a point would need the moving arc there; none of the thesis' models uses one.
  o.initial_value = [&record](const ir::Factor& f) -> std::optional<double> {
    auto it = record.signals.find(f.name);
    if (f.order != 0 || it == record.signals.end() || record.time.size() < 2) return std::nullopt;
    const double at = f.at ? f.at->value() : record.time.front();
    const double k = (at - record.time.front()) / record.step;
    const auto i = static_cast<std::size_t>(std::llround(k));
    if (k < -1e-9 || std::abs(k - std::round(k)) > 1e-6 || i >= it->second.size()) return std::nullopt;
    return it->second[i];
  };
  for (const auto& s : normalized.signals)
    if (s.kind == ir::Signal::Kind::input && !s.definition)
      if (auto it = record.signals.find(s.name); it != record.signals.end()) o.inputs[s.name] = on_grid(it->second);
  auto initial = initial_state_from_record(form, record, std::get<EvaluationOptions>(chosen), start, true);
  if (auto* d = std::get_if<Diagnostic>(&initial)) return *d;
  o.initial = std::get<std::map<std::string, std::vector<double>>>(std::move(initial));
  run.state_evaluation = std::get<EvaluationOptions>(chosen);
  run.start = start;
  run.truncated = static_cast<std::size_t>(to) < record.time.size();
  for (const auto& out : form.outputs) run.recorded.push_back(on_grid(record.signals.at(out.name)));
  // Each output's size on the record scales its state components' tolerance and divergence bound
  // (SimulateOptions::state_scale): the tolerance of 1e-9 means "of the signal", whatever its unit.
  for (std::size_t j = 0; j < form.outputs.size(); ++j) {
    double size = 0;
    for (double y : run.recorded[j])
      if (std::isfinite(y)) size = std::max(size, std::abs(y));
    o.state_scale.insert(o.state_scale.end(), static_cast<std::size_t>(form.outputs[j].order), size > 0 ? size : 1.0);
  }
  return run;
}

std::variant<ValidationSummary, Diagnostic> validate(const ir::Model& normalized, const ExplicitForm& form, const std::vector<double>& parameters,
                                                     const SampledRecord& record, const ValidationOptions& options) {
  auto prepared = record_run(normalized, form, parameters, record, options);
  if (auto* d = std::get_if<Diagnostic>(&prepared)) return *d;
  RecordRun& prepared_run = std::get<RecordRun>(prepared);
  SimulateOptions& o = prepared_run.options;
  const std::vector<Column>& recorded = prepared_run.recorded;  // per output, on o.time

  ValidationSummary v;
  v.record = record.path;
  v.truncated = prepared_run.truncated;
  v.recorded_state = named_state(form, o.initial);
  v.initial_method = options.initial_state;
  std::optional<InitialStateEstimate> start_estimate;  // for the sensitivity test
  if (options.initial_state == InitialState::estimate && o.time.size() >= 2) {
    // With options.method (RK4 by default); ValidationOptions::choose_method changes only the free run below.
    const InitialStateEstimate estimate = estimate_initial_state(normalized, form, o, recorded, start_segment_samples(o.time.size()));
    o.initial = estimate.initial;
    start_estimate = estimate;
    v.start_segment = estimate.segment;
    v.estimate_iterations = estimate.iterations;
  }
  v.initial_state = named_state(form, o.initial);
  if (options.choose_method) o.method = free_run_method(normalized, form);
  if (options.progress)
    o.progress = [&options, &record](std::size_t done, std::size_t total) { options.progress(record.path, done, total); };
  auto run = simulate(normalized, form, o);
  if (auto* d = std::get_if<Diagnostic>(&run)) return *d;
  v.simulation = std::get<SimulationSummary>(std::move(run));

  for (std::size_t j = 0; j < form.outputs.size(); ++j) {
    const Column& y = recorded[j];
    const std::vector<double>& yhat = v.simulation.outputs[j];
    OutputValidation r;
    r.output = form.outputs[j].name;
    // E = y - yhat, eq. 4-1.4: observed - approximated; taken afresh where needed rather than held
    // (a whole record's curve is 80 MB at 10^7 samples; validation.csv takes it the same way).
    auto e = [&](std::size_t i) { return y[i] - yhat[i]; };
    double max_observed = 0, mean = 0, sum_e2 = 0, sum_d2 = 0;
    for (std::size_t i = 0; i < y.size(); ++i) {
      if (!std::isfinite(e(i))) continue;
      ++r.samples;
      mean += y[i];
    }
    if (r.samples) mean /= static_cast<double>(r.samples);
    r.mean = mean;
    // Squares taken relative to the largest error or deviation, so that a record in units of 1e200
    // (or 1e-200) gives the same fit % and a finite RMS error.
    double scale = 0;
    for (std::size_t i = 0; i < y.size(); ++i)
      if (const double ei = e(i); std::isfinite(ei)) scale = std::max({scale, std::abs(ei), std::abs(y[i] - mean)});
    for (std::size_t i = 0; i < y.size(); ++i) {
      const double ei = e(i);
      if (!std::isfinite(ei)) continue;
      max_observed = std::max(max_observed, std::abs(y[i]));
      if (std::abs(ei) > r.max_abs_error) r.max_abs_error = std::abs(ei), r.time_of_max = o.time[i];
      if (scale == 0) continue;
      sum_e2 += (ei / scale) * (ei / scale);
      sum_d2 += ((y[i] - mean) / scale) * ((y[i] - mean) / scale);
    }
    r.percent_error = max_observed > 0 ? 100 * r.max_abs_error / max_observed : NAN;  // eq. 4-1.5
    // A whole run without any error is a fit of 100%, also on a constant record (whose spread is 0).
    r.fit_percent = v.simulation.completed() && r.samples && sum_e2 == 0 ? 100
                    : sum_d2 > 0                                      ? 100 * (1 - std::sqrt(sum_e2 / sum_d2))
                                                                      : NAN;
    r.rms_error = r.samples ? scale * std::sqrt(sum_e2 / static_cast<double>(r.samples)) : NAN;
    r.follows = v.simulation.completed() && r.fit_percent >= kFollowsFitPercent;
    r.spread = r.samples ? scale * std::sqrt(sum_d2 / static_cast<double>(r.samples)) : 0.0;
    r.departs_at = departure(y, yhat, o.time, kDepartureShare * r.spread);
    if (!r.departs_at && !v.simulation.completed()) r.departs_at = v.simulation.stopped_at;
    v.outputs.push_back(r);
    v.recorded.push_back(std::move(prepared_run.recorded[j]));  // not read again
  }
  v.follows = v.simulation.completed() && std::all_of(v.outputs.begin(), v.outputs.end(), [](const OutputValidation& r) { return r.follows; });
  if (options.check_sensitivity && v.simulation.completed() && !v.follows) {
    std::optional<double> departs;
    for (const auto& r : v.outputs)
      if (!r.follows && r.departs_at && (!departs || *r.departs_at < *departs)) departs = r.departs_at;
    if (departs && start_estimate) {
      std::vector<double> noise;  // each output's noise level over the compared samples
      for (const Column& y : v.recorded) noise.push_back(estimate_noise_level(y).sigma);
      v.restarted = restart_within_horizon(normalized, form, record, prepared_run, v, uncertainty_axes(*start_estimate, noise, options.tolerance), noise,
                                           *departs, options);
    }
    if (v.restarted && v.restarted->judged) v.follows = v.restarted->follows;
  }
  if (v.simulation.completed()) {
    // The sentence follows from the numbers: "follow it" only when every output's fit % reaches
    // kFollowsFitPercent; otherwise it names each output that falls short, where it departs and
    // its largest error.
    std::string parts, short_of;
    for (const auto& r : v.outputs) {
      const std::string numbers = fmt::format("max |E[{}]| = {:.4g} at t = {} ({:.3g}% of max |{}|, eq. 4-1.5)", r.output, r.max_abs_error,
                                              time_text(r.time_of_max, record.step, 4), r.percent_error, r.output);
      parts += (parts.empty() ? "" : "; ") + numbers;
      if (r.follows) continue;
      const std::string departs =
          r.departs_at ? fmt::format("departs at t = {} (local RMS error above {:g}% of the standard deviation of {}), ", time_text(*r.departs_at, record.step, 4),
                                     100 * kDepartureShare, r.output)
                       : std::string();
      short_of += fmt::format("{}fit {:.3g}% for {} (below {:g}%), {}{}", short_of.empty() ? "" : "; ", r.fit_percent, r.output, kFollowsFitPercent,
                              departs, numbers);
    }
    v.statement = short_of.empty() ? "The fitted equations, solved from the record, follow it: " + parts + "."
                                   : "The fitted equations, solved from the record, do not follow it: " + short_of + ".";
    if (v.restarted && v.restarted->sensitive) v.statement = v.restarted->statement(short_of, record.step);
  } else {
    v.statement = fmt::format("The fitted equations could not be solved over the whole record: {}. The model does not reproduce the record; "
                              "the numbers below cover the samples before t = {}.",
                              v.simulation.message, time_text(v.simulation.stopped_at.value_or(record.time.front()), record.step, 6));
  }
  return v;
}

std::string ValidationSummary::Restarted::statement(const std::string& free_run, double step) const {
  std::string fits;
  for (const auto& [output, fit] : fit_percent)
    fits += fmt::format("{}fit {:.4g}% for {}{}", fits.empty() ? "" : ", ", fit, output, fit >= kFollowsFitPercent ? "" : fmt::format(" (below {:g}%)", kFollowsFitPercent));
  const std::string twin =
      separates_at.value_or(start) <= start
          ? "the initial state estimated over the start segment is itself uncertain by more than a tenth of an output's spread"
          : fmt::format("started one standard deviation of the estimated initial state away (for the record's noise), their own solution "
                        "separates from this one by t = {}",
                        time_text(separates_at.value_or(start), step, 4));
  const std::string runs_text = fmt::format("restarted from the record every {:.4g} time units ({} runs{}, each from a state estimated over its start "
                                            "and compared up to where its own displaced runs separate from it: {:.3g}% of their samples)",
                                            run_every, runs, run_every > run_duration ? fmt::format(" of {:.4g}", run_duration) : "",
                                            100 * compared_share);
  if (!judged)
    return fmt::format("The fitted equations, solved from the record, do not follow it: {}. But they are as sensitive to their initial state ({}), "
                       "so the departure may be that sensitivity rather than the model; {}.",
                       free_run, twin,
                       runs == 0 ? fmt::format("runs restarted from the record within that horizon would be shorter than {:g} periods of the "
                                               "output that varies fastest ({:.4g}) or than {} samples, too short to judge the model by",
                                               kRestartPeriods, period, kShortestRestart)
                                 : fmt::format("{}, less than {:g}%, too little to judge the model by", runs_text, 100 * kRestartComparedShare));
  if (follows) {
    const std::string why = start_unfitted ? fmt::format("within the segment their initial state was estimated over, whose fit that start therefore "
                                                         "is not; and {} (a chaotic or unstable solution)",
                                                         twin)
                                           : fmt::format("as they must: {}, so no run from a state known only to within the record's noise can "
                                                         "follow it for longer (a chaotic or unstable solution)",
                                                         twin);
    return fmt::format("The fitted equations follow the record within their horizon of predictability: {}, {}. Solved freely over the whole record "
                       "they depart at t = {}, {}. The free run: {}.",
                       runs_text, fits, time_text(free_run_departs_at, step, 4), why, free_run);
  }
  return fmt::format("The fitted equations, solved from the record, do not follow it: {}. Nor when {}, within the horizon their own "
                     "sensitivity to the initial state allows ({}): {}{}.",
                     free_run, runs_text, twin, fits, completed ? "" : "; a restarted run could not be solved to its end");
}

std::string ValidationSummary::report(const std::string& method) const {
  auto listed = [](const std::vector<std::pair<std::string, double>>& state) {
    std::string text;
    for (const auto& [name, value] : state) text += fmt::format("{}{} = {:.6g}", text.empty() ? "" : ", ", name, value);
    return text;
  };
  std::string out = fmt::format("validation (thesis section 2-4): the fitted equations solved by {} against `{}`,\n", method, record);
  const double first = simulation.time.empty() ? 0.0 : simulation.time.front();
  const double step = simulation.time.size() > 1 ? simulation.time[1] - simulation.time[0] : 0.0;
  if (initial_method == InitialState::estimate && start_segment > 0)
    out += fmt::format("  from t = {} with {} (estimated by least squares over the first {} samples, to t = {}, {} step{};\n"
                       "  the record gives {}: sample and moving-arc derivatives)\n",
                       time_text(first, step, 6), listed(initial_state), start_segment,
                       time_text(simulation.time.size() >= start_segment ? simulation.time[start_segment - 1] : first, step, 6), estimate_iterations,
                       estimate_iterations == 1 ? "" : "s", listed(recorded_state));
  else
    out += fmt::format("  from t = {} with {} (taken from the record; derivatives by the moving arc)\n", time_text(first, step, 6), listed(initial_state));
  out += fmt::format("  {:<10} {:>8} {:>12} {:>10} {:>16} {:>10} {:>12}\n", "output", "samples", "max |E|", "at t", "%E (eq. 4-1.5)", "fit %", "RMS E");
  for (const auto& r : outputs)
    out += fmt::format("  {:<10} {:>8} {:>12.4g} {:>10} {:>16.3g} {:>10.4g} {:>12.4g}\n", r.output, r.samples, r.max_abs_error, time_text(r.time_of_max, step, 4),
                       r.percent_error, r.fit_percent, r.rms_error);
  out += "  " + statement + "\n";
  return out;
}

FitValidation validate_fit(const ir::Model& normalized, const std::variant<ExplicitForm, Diagnostic>& form, const FitSummary& summary,
                           const std::vector<const SampledRecord*>& records, std::size_t fitted_records, const EvaluationOptions& evaluation,
                           std::size_t max_samples, InitialState initial_state, const std::vector<double>* refined,
                           const std::string& refined_by,
                           const std::function<void(const std::string& record, std::size_t done, std::size_t total)>& progress,
                           bool check_sensitivity) {
  FitValidation v;
  v.max_samples = max_samples;
  if (!summary.is_solution_usable()) {
    v.note = "skipped: the fit is rank deficient, so its parameters are not worth simulating";
    return v;
  }
  if (auto* d = std::get_if<Diagnostic>(&form)) {
    v.note = "skipped: " + d->message;
    return v;
  }
  const std::vector<double> parameters = refined ? *refined : fitted_parameter_values(normalized, summary, 0.0);
  ValidationOptions o;
  o.choose_method = true;
  v.method = free_run_description(free_run_method(normalized, std::get<ExplicitForm>(form)), o);
  if (refined) v.method += ", with the parameters " + refined_by;
  o.evaluation = evaluation;
  o.max_samples = max_samples;
  o.initial_state = initial_state;
  o.progress = progress;
  o.check_sensitivity = check_sensitivity;
  for (std::size_t r = 0; r < records.size(); ++r) {
    auto run = validate(normalized, std::get<ExplicitForm>(form), parameters, *records[r], o);
    if (auto* d = std::get_if<Diagnostic>(&run)) {
      if (r >= fitted_records) {  // a --validate record the user named: its problem is an error
        v.failed_record = *d;
        v.failed_path = records[r]->path;
        return v;
      }
      v.note = fmt::format("skipped for `{}`: {}", records[r]->path, d->message);
      continue;
    }
    v.runs.push_back(std::get<ValidationSummary>(std::move(run)));
  }
  return v;
}

std::optional<double> simulation_rms_error(const ir::Model& normalized, const ExplicitForm& form, const std::vector<ParameterIndex>& subset,
                                           const std::vector<double>& values, const std::vector<SampledRecord>& records,
                                           const EvaluationOptions& evaluation, std::size_t max_samples) {
  std::vector<double> parameters(normalized.parameters.size(), 0.0);
  for (std::size_t i = 0; i < subset.size(); ++i)
    // The derivative form's parameters come first in the fitted model's order (integrate_pass.cpp).
    if (!subset[i].record && subset[i].parameter < parameters.size()) parameters[subset[i].parameter] = values[i];
  ValidationOptions v;
  v.choose_method = true;
  v.evaluation = evaluation;
  v.max_samples = max_samples;
  double squares = 0;
  std::size_t count = 0;
  for (const auto& record : records) {
    auto run = validate(normalized, form, parameters, record, v);
    if (!std::holds_alternative<ValidationSummary>(run)) return std::nullopt;
    const ValidationSummary& s = std::get<ValidationSummary>(run);
    if (!s.simulation.completed()) return std::numeric_limits<double>::infinity();
    for (const auto& out : s.outputs) squares += out.rms_error * out.rms_error * static_cast<double>(out.samples), count += out.samples;
  }
  return count ? std::sqrt(squares / static_cast<double>(count)) : std::optional<double>();
}

}  // namespace sidc
