// The figures of issue 5, built from plain vectors, each in the engineer's words and named after
// the thesis figure it corresponds to. Builders only arrange numbers into a Figure (figure.hpp);
// gnuplot_renderer.hpp draws it. They do not depend on the simulation or validation code: the
// caller passes the recorded and simulated samples, the estimates and the truths.
//
// Relies on: runtime/solve/residual_correlation.hpp (for the correlation figures) and fmt.
// Guarantees: no builder throws or aborts; mismatched lengths are not checked here (the renderer
// reports them as an invalid figure). Percentages follow eq. 4-1.5:
//   %E = max |observed - approximated| / max |observed| * 100,
// with the divisor stated on the figure (the thesis notes it under Figs. 4-1.8 to 4-1.12).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "report/figure.hpp"
#include "runtime/solve/residual_correlation.hpp"

namespace sidc {

// A signal's name and unit, for axis labels: "y [m]", or "y" when the unit is unknown.
struct SignalLabel {
  std::string name;
  std::string unit;
  std::string axis() const { return unit.empty() ? name : name + " [" + unit + "]"; }
};

// One error curve E = observed - approximated (eq. 4-1.4) over a shared abscissa.
struct ErrorCurve {
  std::string label;                       // e.g. "E[y']"
  std::vector<double> error;               // observed - approximated, per abscissa sample
  std::optional<double> percent_divisor;   // eq. 4-1.5's divisor, max |observed|; none = no %
};

// Summary numbers written on an error figure (and usable in a report table).
struct ErrorStatistics {
  double max_abs = 0;       // max |E| over finite samples
  double at = 0;            // abscissa where it occurs
  double mean = 0;          // arithmetic mean of E (Fig. 4-2.7 gives it)
  double standard_error = 0;  // sqrt(sum E^2 / n), the thesis' standard error (Table 4-1.2 footnote)
  std::size_t n = 0;        // finite samples
};
ErrorStatistics error_statistics(const std::vector<double>& x, const std::vector<double>& error);

// Figs. 4-2.5 / 4-2.6: the recorded output as points and the free-run solution of the fitted
// equations as a line, over time. Stem "simulated_<output>".
Figure recorded_vs_simulated_figure(const SignalLabel& time, const SignalLabel& output, const std::vector<double>& t,
                                    const std::vector<double>& recorded, const std::vector<double>& simulated);

// Figs. 4-1.11 / 4-1.12 / 4-2.7: error curves over a shared abscissa, with max |E|, its eq. 4-1.5
// percentage, the mean and the standard error of each curve written on the figure.
Figure error_curves_figure(const std::string& stem, const std::string& title, const SignalLabel& abscissa,
                           const std::string& y_label, const std::vector<double>& x, const std::vector<ErrorCurve>& curves);

// Fig. 4-2.7 for one output: E[y] = recorded - simulated over time, % of max |recorded| (eq. 4-1.5).
// Stem "error_<output>".
Figure simulation_error_figure(const SignalLabel& time, const SignalLabel& output, const std::vector<double>& t,
                               const std::vector<double>& recorded, const std::vector<double>& simulated);

// Figs. 4-1.13 / 4-1.14: a reconstructed function (e.g. the damper force c(y') from the fitted
// terms that make it up) over the range the record covers, alone or over a supplied truth (dashed).
// Stem "function_<name>".
Figure reconstructed_function_figure(const std::string& function_name, const SignalLabel& argument,
                                     const SignalLabel& value, const std::vector<double>& x,
                                     const std::vector<double>& fitted,
                                     const std::optional<std::vector<double>>& truth);

// Fig. 4-1.11: the error truth - fitted of a reconstructed function over its argument, with
// eq. 4-1.5's percentage of max |truth|. Stem "function_error_<name>".
Figure reconstructed_function_error_figure(const std::string& function_name, const SignalLabel& argument,
                                           const SignalLabel& value, const std::vector<double>& x,
                                           const std::vector<double>& fitted, const std::vector<double>& truth);

// One derivative estimate against the exact derivative (supplied by the user).
struct DerivativeComparison {
  int order = 1;                   // 1 for y', 2 for y''
  std::vector<double> estimated;   // the moving-arc estimate (section 3-1), NaN where not evaluated
  std::vector<double> exact;
};

// Figs. 4-1.8 / 4-1.9: E[y^(k)] = exact - estimated over time for each order, with eq. 4-1.5's
// percentage of max |exact|. `setting` is written in the title (e.g. "Delta = 0.020").
// Stem "derivative_error_<signal>".
Figure derivative_error_figure(const SignalLabel& time, const SignalLabel& signal, const std::vector<double>& t,
                               const std::vector<DerivativeComparison>& derivatives, const std::string& setting);

// Fig. 4-1.7: the phase plane portrait y' against y, the start marked. Stem "phase_plane_<signal>".
Figure phase_plane_figure(const SignalLabel& signal, const std::string& time_unit, const std::vector<double>& y,
                          const std::vector<double>& y_dot);

// Residual analysis (no thesis figure; MATLAB's `resid`): the autocorrelation of the equation
// residuals for lags 0..L with the band. `group` names the equations (stem suffix, e.g. "1").
// Stem "residual_autocorrelation_<group>".
Figure residual_autocorrelation_figure(const ResidualCorrelationSummary& summary, const std::string& group);

// The cross-correlation of the residuals with input `input` (index into summary.cross), lags
// -L..L. Stem "residual_cross_<input>_<group>".
Figure residual_cross_correlation_figure(const ResidualCorrelationSummary& summary, std::size_t input,
                                         const std::string& group);

// A file stem from a signal or function name: characters outside [A-Za-z0-9_-] become '_',
// primes become 'p' ("y'" -> "yp").
std::string figure_stem(const std::string& name);

// Thesis chapter V: one parameter's local estimates along a record (sidc fit --local), with its 95%
// band (estimate +- 1.96 standard errors) dashed; windows without an estimate are gaps. At most
// `most` points are drawn (every k-th window), so a record of 10^6 windows stays a light picture.
Figure local_estimate_figure(const std::string& parameter, const std::string& stem_suffix, const SignalLabel& time, const std::string& what,
                             const std::vector<double>& t, const std::vector<double>& estimate, const std::vector<double>& standard_error,
                             std::size_t most = 2000);

}  // namespace sidc
