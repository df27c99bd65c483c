#include "runtime/operators/test_functions.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include <fmt/format.h>
#include <unsupported/Eigen/FFT>

#include "diagnostics/data_catalogue.hpp"

namespace sidc {
namespace {

constexpr std::size_t kLongestSegment = 16384;  // Welch segments: fine enough in frequency, cheap
constexpr double kAboveFloor = 10;             // the corner: where the spectrum falls to 10x its noise floor

// Coefficients of (1 - s^2)^p in powers of s, then differentiated k times.
std::vector<double> bump_polynomial(int p, int k) {
  std::vector<double> c(static_cast<std::size_t>(2 * p + 1), 0.0);
  double binomial = 1;
  for (int i = 0; i <= p; ++i) {
    c[static_cast<std::size_t>(2 * i)] = (i % 2 ? -1.0 : 1.0) * binomial;
    binomial = binomial * (p - i) / (i + 1);
  }
  for (int d = 0; d < k; ++d) {
    for (std::size_t i = 1; i < c.size(); ++i) c[i - 1] = c[i] * static_cast<double>(i);
    if (!c.empty()) c.pop_back();
  }
  return c;
}

double horner(const std::vector<double>& c, double s) {
  double v = 0;
  for (auto it = c.rbegin(); it != c.rend(); ++it) v = v * s + *it;
  return v;
}

// Subdomains of half-width m over `samples` samples: one every max(1, m/4) samples, the last
// ending at the last sample.
std::vector<std::size_t> centres_for(std::size_t samples, std::size_t m) {
  std::vector<std::size_t> centres;
  if (samples < 2 * m + 1) return centres;
  const std::size_t stride = std::max<std::size_t>(1, m / 4), last = samples - 1 - m;
  for (std::size_t c = m; c <= last; c += stride) centres.push_back(c);
  if (centres.back() != last) centres.push_back(last);
  return centres;
}

}  // namespace

namespace {

struct Spectrum {
  double corner = 0;    // f_c: where the power falls to its noise floor
  double centroid = 0;  // the power-weighted mean frequency below f_c: the signal's own time scale
};

Spectrum spectrum_of(std::span<const double> values, double step) {
  const std::size_t n = values.size();
  if (n < 16) return {};
  std::size_t L = 16;
  while (L * 2 <= std::min(n, kLongestSegment)) L *= 2;
  std::vector<double> window(L), power(L / 2 + 1, 0.0);
  double window_energy = 0;
  for (std::size_t i = 0; i < L; ++i) {
    window[i] = 0.5 * (1 - std::cos(2 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(L - 1)));
    window_energy += window[i] * window[i];
  }
  std::vector<std::size_t> starts;
  for (std::size_t s = 0; s + L <= n; s += L / 2) starts.push_back(s);
  if (starts.back() + L != n) starts.push_back(n - L);
  Eigen::FFT<double> fft;
  std::vector<double> segment(L);
  std::vector<std::complex<double>> spectrum;
  for (std::size_t s : starts) {
    // Each segment's straight line taken off first: a trend would leak over the whole band.
    double mean_i = (static_cast<double>(L) - 1) / 2, mean_y = 0, sxy = 0, sxx = 0;
    for (std::size_t i = 0; i < L; ++i) mean_y += values[s + i];
    mean_y /= static_cast<double>(L);
    for (std::size_t i = 0; i < L; ++i) {
      const double di = static_cast<double>(i) - mean_i;
      sxy += di * (values[s + i] - mean_y), sxx += di * di;
    }
    const double slope = sxy / sxx;
    for (std::size_t i = 0; i < L; ++i)
      segment[i] = window[i] * (values[s + i] - mean_y - slope * (static_cast<double>(i) - mean_i));
    fft.fwd(spectrum, segment);
    for (std::size_t f = 0; f < power.size(); ++f) power[f] += std::norm(spectrum[f]) / window_energy;
  }
  // The white-noise floor: the median power over the upper half band.
  std::vector<double> upper(power.begin() + static_cast<std::ptrdiff_t>(L / 4), power.end());
  std::nth_element(upper.begin(), upper.begin() + static_cast<std::ptrdiff_t>(upper.size() / 2), upper.end());
  const double floor = upper[upper.size() / 2];
  // The highest frequency whose power, averaged over 5 neighbouring bins, stands clear of the floor.
  for (std::size_t f = power.size() - 1; f >= 1; --f) {
    double sum = 0;
    int count = 0;
    for (std::size_t g = f >= 3 ? f - 2 : 1; g <= std::min(power.size() - 1, f + 2); ++g) sum += power[g], ++count;
    if (sum / count > kAboveFloor * floor && sum > 0) {
      Spectrum s;
      s.corner = static_cast<double>(f) / (static_cast<double>(L) * step);
      double power_below = 0, moment = 0;
      for (std::size_t g = 1; g <= f; ++g) power_below += power[g], moment += power[g] * static_cast<double>(g);
      s.centroid = power_below > 0 ? moment / power_below / (static_cast<double>(L) * step) : s.corner;
      return s;
    }
  }
  return {};
}

}  // namespace

double corner_frequency(std::span<const double> values, double step) { return spectrum_of(values, step).corner; }

std::variant<TestFunctionGrid, Diagnostic> choose_test_functions(const std::vector<std::span<const double>>& outputs,
                                                                 std::size_t samples, double step, int highest_order,
                                                                 std::size_t fewest_rows, std::string_view record) {
  TestFunctionGrid grid;
  // p - 1 >= k: phi^(k) must still vanish at the ends for the last move by parts; eight orders more
  // make the trapezoid rule's end corrections (Euler-Maclaurin) negligible, below 1e-9 relative from
  // 3p samples per half-width on (measured), and phi close to a Gaussian for the width rule.
  grid.degree = highest_order + 8;
  const std::size_t narrowest = static_cast<std::size_t>(3 * grid.degree);
  std::size_t widest = samples > 0 ? (samples - 1) / 2 : 0;
  while (widest >= narrowest && centres_for(samples, widest).size() < fewest_rows) --widest;
  if (widest < narrowest)
    return diag::weak_form_too_short(record, samples, 2 * narrowest + 1 + (fewest_rows - 1) * std::max<std::size_t>(1, narrowest / 4),
                                     fewest_rows);
  double centroid = 0;
  for (const auto& y : outputs) {
    const Spectrum s = spectrum_of(y, step);
    grid.corner_frequency = std::max(grid.corner_frequency, s.corner);
    centroid = std::max(centroid, s.centroid);
  }
  std::size_t m = widest;
  if (grid.corner_frequency > 0) {
    // Passing below f_c; and at least a quarter of the signal's own period wide, or the integral
    // of phi^(k) * y is a near cancellation whose rounding and quadrature errors the fit amplifies
    // (a record with no noise has its corner near Nyquist).
    const double passing = std::sqrt(2.0 * grid.degree) / (std::numbers::pi * grid.corner_frequency), spanning = 0.25 / centroid;
    const double h = std::max(passing, spanning);
    m = static_cast<std::size_t>(std::clamp(std::round(h / step), static_cast<double>(narrowest), static_cast<double>(widest)));
    grid.reason = passing >= spanning
                      ? fmt::format("the outputs' spectrum meets its noise floor at f_c = {:.4g}; phi passes below it", grid.corner_frequency)
                      : fmt::format("a quarter period of the outputs' mean frequency {:.4g} (their spectrum meets its noise floor at "
                                    "f_c = {:.4g}, far above)", centroid, grid.corner_frequency);
  } else {
    grid.reason = "no output stands above its noise floor: the widest subdomains";
  }
  if (m == narrowest && grid.corner_frequency > 0) grid.reason += " (the narrowest the quadrature allows)";
  if (m == widest && grid.corner_frequency > 0) grid.reason += fmt::format(" (as wide as {} subdomains allow)", fewest_rows);
  grid.half_width = m;
  grid.centres = centres_for(samples, m);
  return grid;
}

std::vector<double> test_function_weights(const TestFunctionGrid& grid, int k, double step) {
  const auto m = static_cast<double>(grid.half_width);
  const std::vector<double> c = bump_polynomial(grid.degree, k);
  const double scale = step / std::pow(m * step, k);  // trapezoid weight times d^k s / dt^k = h^-k
  std::vector<double> w(2 * grid.half_width + 1);
  for (std::size_t i = 0; i < w.size(); ++i) w[i] = scale * horner(c, (static_cast<double>(i) - m) / m);
  return w;  // the end points carry phi^(k)(+-1) = 0 for k < p: the trapezoid's halves need no care
}

}  // namespace sidc
