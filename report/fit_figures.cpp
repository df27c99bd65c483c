// Builders of the issue-5 figures; see fit_figures.hpp.
#include "report/fit_figures.hpp"

#include <cmath>

#include <fmt/format.h>

namespace sidc {
namespace {

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v)
    if (std::isfinite(x)) m = std::max(m, std::fabs(x));
  return m;
}

std::vector<double> difference(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> d(std::min(a.size(), b.size()));
  for (std::size_t i = 0; i < d.size(); ++i) d[i] = a[i] - b[i];
  return d;
}

std::string primes(int order) {
  if (order <= 3) return std::string(static_cast<std::size_t>(std::max(order, 0)), '\'');
  return fmt::format("^({})", order);
}

std::string derivative_unit(const SignalLabel& signal, const SignalLabel& time, int order) {
  if (signal.unit.empty() || time.unit.empty()) return "";
  return order == 1 ? signal.unit + "/" + time.unit : fmt::format("{}/{}^{}", signal.unit, time.unit, order);
}

}  // namespace

std::string figure_stem(const std::string& name) {
  std::string out;
  for (char c : name) {
    if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-') out += c;
    else if (c == '\'') out += 'p';
    else out += '_';
  }
  return out.empty() ? std::string("unnamed") : out;
}

ErrorStatistics error_statistics(const std::vector<double>& x, const std::vector<double>& error) {
  ErrorStatistics s;
  long double sum = 0, squares = 0;
  for (std::size_t i = 0; i < error.size(); ++i) {
    const double e = error[i];
    if (!std::isfinite(e)) continue;
    ++s.n;
    sum += e;
    squares += static_cast<long double>(e) * e;
    if (std::fabs(e) > s.max_abs || s.n == 1) {
      s.max_abs = std::fabs(e);
      s.at = i < x.size() ? x[i] : NAN;
    }
  }
  if (s.n > 0) {
    s.mean = static_cast<double>(sum / static_cast<long double>(s.n));
    s.standard_error = static_cast<double>(std::sqrt(squares / static_cast<long double>(s.n)));
  }
  return s;
}

Figure recorded_vs_simulated_figure(const SignalLabel& time, const SignalLabel& output, const std::vector<double>& t,
                                    const std::vector<double>& recorded, const std::vector<double>& simulated) {
  Figure figure;
  figure.name = "simulated_" + figure_stem(output.name);
  figure.title = fmt::format("{}({}): record and solution of the fitted equations (cf. Figs. 4-2.5, 4-2.6)",
                             output.name, time.name);
  figure.x_label = time.axis();
  figure.y_label = output.axis();
  figure.curves.push_back({fmt::format("recorded {}", output.name), t, recorded, Curve::Style::points});
  figure.curves.push_back({fmt::format("solution of the fitted equations"), t, simulated, Curve::Style::line});
  return figure;
}

Figure error_curves_figure(const std::string& stem, const std::string& title, const SignalLabel& abscissa,
                           const std::string& y_label, const std::vector<double>& x,
                           const std::vector<ErrorCurve>& curves) {
  Figure figure;
  figure.name = stem;
  figure.title = title;
  figure.x_label = abscissa.axis();
  figure.y_label = y_label;
  figure.zero_axis = true;
  for (const auto& curve : curves) {
    figure.curves.push_back({curve.label, x, curve.error, Curve::Style::line});
    const auto s = error_statistics(x, curve.error);
    // Short enough to fit the picture's width: label, max |E| and where, eq. 4-1.5's %, mean and
    // the standard error sqrt(sum E^2 / n), as Figs. 4-1.8 and 4-2.7 note them.
    const std::string name = curve.label.substr(0, curve.label.find(" ["));
    std::string note = fmt::format("{}: max |E| = {:.3g} at {} = {:.4g}", name, s.max_abs, abscissa.name, s.at);
    if (curve.percent_divisor && *curve.percent_divisor > 0)
      note += fmt::format(" ({:.2g}% of {:.4g})", 100 * s.max_abs / *curve.percent_divisor, *curve.percent_divisor);
    note += fmt::format("; mean {:.2g}, s.e. {:.3g}", s.mean, s.standard_error);
    figure.notes.push_back(std::move(note));
  }
  return figure;
}

Figure simulation_error_figure(const SignalLabel& time, const SignalLabel& output, const std::vector<double>& t,
                               const std::vector<double>& recorded, const std::vector<double>& simulated) {
  const std::string label = fmt::format("E[{}]", output.name);
  return error_curves_figure(
      "error_" + figure_stem(output.name),
      fmt::format("Error curve {} = recorded - solution of the fitted equations (cf. Fig. 4-2.7)", label),
      time, output.unit.empty() ? label : label + " [" + output.unit + "]", t,
      {{label, difference(recorded, simulated), max_abs(recorded)}});
}

Figure reconstructed_function_figure(const std::string& function_name, const SignalLabel& argument,
                                     const SignalLabel& value, const std::vector<double>& x,
                                     const std::vector<double>& fitted,
                                     const std::optional<std::vector<double>>& truth) {
  Figure figure;
  figure.name = "function_" + figure_stem(function_name);
  figure.title = truth ? fmt::format("{} from the fitted terms and the supplied truth (cf. Figs. 4-1.13, 4-1.14)",
                                     function_name)
                       : fmt::format("{} from the fitted terms over the record's range (cf. Figs. 4-1.13, 4-1.14)",
                                     function_name);
  figure.x_label = argument.axis();
  figure.y_label = value.axis();
  figure.zero_axis = true;
  if (truth) figure.curves.push_back({"supplied truth", x, *truth, Curve::Style::dashed_line});
  figure.curves.push_back({"fitted", x, fitted, Curve::Style::line});
  return figure;
}

Figure reconstructed_function_error_figure(const std::string& function_name, const SignalLabel& argument,
                                           const SignalLabel& value, const std::vector<double>& x,
                                           const std::vector<double>& fitted, const std::vector<double>& truth) {
  const std::string label = fmt::format("E[{}]", function_name);
  return error_curves_figure("function_error_" + figure_stem(function_name),
                             fmt::format("Error curve {} = truth - fitted (cf. Figs. 4-1.11, 4-1.12)", label),
                             argument, value.unit.empty() ? label : label + " [" + value.unit + "]", x,
                             {{label, difference(truth, fitted), max_abs(truth)}});
}

Figure derivative_error_figure(const SignalLabel& time, const SignalLabel& signal, const std::vector<double>& t,
                               const std::vector<DerivativeComparison>& derivatives, const std::string& setting) {
  std::vector<ErrorCurve> curves;
  std::string names;
  for (const auto& d : derivatives) {
    const std::string label = fmt::format("E[{}{}]", signal.name, primes(d.order));
    const std::string unit = derivative_unit(signal, time, d.order);
    curves.push_back({unit.empty() ? label : label + " [" + unit + "]", difference(d.exact, d.estimated),
                      max_abs(d.exact)});
    names += (names.empty() ? "" : " and ") + label;
  }
  auto figure = error_curves_figure(
      "derivative_error_" + figure_stem(signal.name),
      fmt::format("Errors of the derivative estimates {}{} (cf. Figs. 4-1.8, 4-1.9)", names,
                  setting.empty() ? std::string() : "; " + setting),
      time, "", t, curves);
  // Each order on its own scale (E[y''] is typically 20 to 50 times E[y']): the first on the left
  // axis, the second on the right, as the thesis draws them with two scales.
  figure.y_label = curves.empty() ? "E = exact - estimate" : curves[0].label + " = exact - estimate";
  if (figure.curves.size() == 2) {
    figure.curves[1].right_axis = true;
    figure.y2_label = curves[1].label;
  }
  return figure;
}

Figure phase_plane_figure(const SignalLabel& signal, const std::string& time_unit, const std::vector<double>& y,
                          const std::vector<double>& y_dot) {
  Figure figure;
  figure.name = "phase_plane_" + figure_stem(signal.name);
  figure.title = fmt::format("Phase plane portrait {}' against {} (cf. Fig. 4-1.7)", signal.name, signal.name);
  figure.x_label = signal.axis();
  const SignalLabel rate{signal.name + "'", signal.unit.empty() || time_unit.empty() ? "" : signal.unit + "/" + time_unit};
  figure.y_label = rate.axis();
  figure.zero_axis = true;
  figure.curves.push_back({"", y, y_dot, Curve::Style::line});
  if (!y.empty() && !y_dot.empty())
    figure.curves.push_back({"start", {y.front()}, {y_dot.front()}, Curve::Style::points});
  figure.vertical_lines.push_back({0.0, ""});
  return figure;
}

Figure residual_autocorrelation_figure(const ResidualCorrelationSummary& summary, const std::string& group) {
  Figure figure;
  figure.name = "residual_autocorrelation_" + figure_stem(group);
  figure.title = fmt::format("Autocorrelation of the equation residuals, equations {} (whiteness test)", group);
  figure.x_label = "lag k [samples]";
  figure.y_label = "r_ee(k)";
  figure.zero_axis = true;
  std::vector<double> lags(summary.autocorrelation.lags.begin(), summary.autocorrelation.lags.end());
  figure.curves.push_back({"r_ee(k)", lags, summary.autocorrelation.values, Curve::Style::impulses});
  figure.band = HorizontalBand{-summary.band, summary.band,
                               fmt::format("{:.0f}% band +-{:.3f}/sqrt(N), N = {}", summary.confidence_level * 100,
                                           summary.z, summary.n)};
  figure.notes.push_back(summary.autocorrelation.computed ? summary.autocorrelation.verdict : summary.verdict);
  return figure;
}

Figure residual_cross_correlation_figure(const ResidualCorrelationSummary& summary, std::size_t input,
                                         const std::string& group) {
  Figure figure;
  const CorrelationCurve empty;
  const auto& curve = input < summary.cross.size() ? summary.cross[input] : empty;
  figure.name = "residual_cross_" + figure_stem(curve.name) + "_" + figure_stem(group);
  figure.title = fmt::format("Cross-correlation of the residuals, equations {}, with input {}", group, curve.name);
  figure.x_label = fmt::format("lag k [samples] (k > 0: {} earlier than the residual)", curve.name);
  figure.y_label = fmt::format("r_e{}(k)", curve.name);
  figure.zero_axis = true;
  std::vector<double> lags(curve.lags.begin(), curve.lags.end());
  figure.curves.push_back({fmt::format("r_e{}(k)", curve.name), lags, curve.values, Curve::Style::impulses});
  figure.band = HorizontalBand{-summary.band, summary.band,
                               fmt::format("{:.0f}% band +-{:.3f}/sqrt(N), N = {}", summary.confidence_level * 100,
                                           summary.z, summary.n)};
  figure.notes.push_back(curve.verdict);
  return figure;
}

Figure local_estimate_figure(const std::string& parameter, const std::string& stem_suffix, const SignalLabel& time, const std::string& what,
                             const std::vector<double>& t, const std::vector<double>& estimate, const std::vector<double>& standard_error,
                             std::size_t most) {
  Figure figure;
  figure.name = "local_" + figure_stem(parameter) + stem_suffix;
  figure.title = fmt::format("Local estimate of {} along the record, {} (thesis chapter V)", parameter, what);
  figure.x_label = time.axis() + " (window centre)";
  figure.y_label = parameter;
  const std::size_t every = std::max<std::size_t>(1, (t.size() + most - 1) / std::max<std::size_t>(most, 1));
  Curve value{parameter, {}, {}, Curve::Style::line}, low{"95% band", {}, {}, Curve::Style::dashed_line}, high{"", {}, {}, Curve::Style::dashed_line};
  high.colour_of = 1;  // the band's two edges alike
  for (std::size_t k = 0; k < t.size(); k += every) {
    const double band = 1.96 * standard_error[k];
    value.x.push_back(t[k]);
    value.y.push_back(estimate[k]);
    low.x.push_back(t[k]);
    low.y.push_back(estimate[k] - band);
    high.x.push_back(t[k]);
    high.y.push_back(estimate[k] + band);
  }
  figure.curves = {std::move(value), std::move(low), std::move(high)};
  if (every > 1) figure.notes.push_back(fmt::format("every {}th window of {} drawn", every, t.size()));
  return figure;
}

}  // namespace sidc
