#include "runtime/operators/simpson.hpp"

#include <cmath>
#include <fmt/format.h>

#include "diagnostics/data_catalogue.hpp"

namespace sidc {

std::vector<double> cumulative_simpson(std::span<const double> f, double delta) {
  const std::size_t n = f.size();
  std::vector<double> integral(n, 0.0);
  if (n < 2) return integral;
  const double h = delta;
  if (n == 2) {
    integral[1] = h / 2 * (f[0] + f[1]);
    return integral;
  }
  // Even samples: composite Simpson over pairs of intervals (thesis 3-2).
  for (std::size_t i = 2; i < n; i += 2) integral[i] = integral[i - 2] + h / 3 * (f[i - 2] + 4 * f[i - 1] + f[i]);
  // Odd samples: the even sample before, plus one interval of the cubic through four samples
  // (the parabola through three when only three exist).
  integral[1] = n == 3 ? h / 12 * (5 * f[0] + 8 * f[1] - f[2]) : h / 24 * (9 * f[0] + 19 * f[1] - 5 * f[2] + f[3]);
  for (std::size_t i = 3; i < n; i += 2)
    integral[i] = integral[i - 1] + h / 24 * (f[i - 3] - 5 * f[i - 2] + 19 * f[i - 1] + 9 * f[i]);
  return integral;
}

std::vector<double> cumulative_trapezoid(std::span<const double> f, double delta) {
  std::vector<double> integral(f.size(), 0.0);
  for (std::size_t i = 1; i < f.size(); ++i) integral[i] = integral[i - 1] + delta / 2 * (f[i - 1] + f[i]);
  return integral;
}

bool IntegrationOptions::is_valid(std::string* why) const {
  if (smoothing_window == 0) return true;
  DerivativeOptions smoothing;
  smoothing.window = smoothing_window;
  smoothing.polyorder = smoothing_polyorder;
  return smoothing.is_valid(why);
}

std::variant<std::vector<double>, Diagnostic> cumulative_integral(std::span<const double> values, double delta,
                                                                  const IntegrationOptions& options) {
  const char* operation = "an integral";
  if (std::string why; !options.is_valid(&why)) return data_diag::invalid_signal_options(operation, why);
  if (!(delta > 0) || !std::isfinite(delta))
    return data_diag::invalid_signal_options(operation, "the sample spacing must be a positive number");
  std::vector<double> smoothed;
  std::span<const double> integrand = values;
  if (options.smoothing_window > 0) {
    DerivativeOptions smoothing;
    smoothing.window = options.smoothing_window;
    smoothing.polyorder = options.smoothing_polyorder;
    smoothing.edges = DerivativeOptions::Edges::shorten;
    auto result = estimate_derivative(values, delta, 0, smoothing);
    if (auto* d = std::get_if<Diagnostic>(&result)) return std::move(*d);
    smoothed = std::get<std::vector<double>>(std::move(result));
    integrand = smoothed;
  }
  return options.rule == IntegrationOptions::Rule::simpson ? cumulative_simpson(integrand, delta)
                                                           : cumulative_trapezoid(integrand, delta);
}

std::string CumulativeIntegralOperator::name() const {
  std::string rule = options_.rule == IntegrationOptions::Rule::simpson ? "Simpson's rule" : "trapezoid rule";
  if (options_.smoothing_window > 0)
    rule += fmt::format(" after a {}-point moving arc of order {}", options_.smoothing_window, options_.smoothing_polyorder);
  return rule;
}

std::variant<std::vector<double>, Diagnostic> CumulativeIntegralOperator::apply(std::span<const double> samples, double step) const {
  return cumulative_integral(samples, step, options_);
}

}  // namespace sidc
