#include "runtime/operators/savitzky_golay.hpp"

#include <algorithm>
#include <fmt/format.h>
#include <cmath>
#include <limits>
#include <tuple>

#include "diagnostics/data_catalogue.hpp"
#include "runtime/not_a_number.hpp"

namespace sidc {
namespace {

// The least-squares weights for unit spacing. With offsets x_i = i - position scaled to
// s_i = x_i / scale (|s_i| <= 1, which keeps the Vandermonde matrix A well conditioned), the
// fitted polynomial is sum_k b_k s^k with b = A^+ y = R^-1 Q^T y (A = QR); its derivative of
// order d at s = 0 is d! b_d / scale^d. So the weights are d! / scale^d * Q z with R^T z = e_d.
// Q and R come from modified Gram-Schmidt with one reorthogonalisation, in long double: the
// weights come out within about 1e-17 of the exact rationals before rounding to double.
std::vector<double> unit_spacing_weights(int window, int polyorder, int derivative, int position) {
  const auto rows = static_cast<std::size_t>(window);
  const auto cols = static_cast<std::size_t>(polyorder + 1);
  const int reach = std::max(position, window - 1 - position);
  const long double scale = reach > 0 ? reach : 1;
  std::vector<std::vector<long double>> q(cols, std::vector<long double>(rows));  // column k of A, then of Q
  for (std::size_t i = 0; i < rows; ++i) {
    const long double s = static_cast<long double>(static_cast<int>(i) - position) / scale;
    long double power = 1;
    for (std::size_t k = 0; k < cols; ++k) {
      q[k][i] = power;
      power *= s;
    }
  }
  std::vector<std::vector<long double>> r(cols, std::vector<long double>(cols, 0.0L));
  for (std::size_t k = 0; k < cols; ++k) {
    for (int sweep = 0; sweep < 2; ++sweep) {
      for (std::size_t j = 0; j < k; ++j) {
        long double projection = 0;
        for (std::size_t i = 0; i < rows; ++i) projection += q[j][i] * q[k][i];
        for (std::size_t i = 0; i < rows; ++i) q[k][i] -= projection * q[j][i];
        r[j][k] += projection;
      }
    }
    long double norm = 0;
    for (std::size_t i = 0; i < rows; ++i) norm += q[k][i] * q[k][i];
    norm = std::sqrt(norm);
    r[k][k] = norm;
    for (std::size_t i = 0; i < rows; ++i) q[k][i] /= norm;
  }
  // Forward substitution for R^T z = e_d (R upper triangular, so R^T is lower triangular).
  const auto d = static_cast<std::size_t>(derivative);
  std::vector<long double> z(cols, 0.0L);
  for (std::size_t k = 0; k < cols; ++k) {
    long double sum = k == d ? 1.0L : 0.0L;
    for (std::size_t j = 0; j < k; ++j) sum -= r[j][k] * z[j];
    z[k] = sum / r[k][k];
  }
  long double factor = 1;
  for (int k = 2; k <= derivative; ++k) factor *= k;
  for (int k = 0; k < derivative; ++k) factor /= scale;
  std::vector<double> weights(rows);
  for (std::size_t i = 0; i < rows; ++i) {
    long double w = 0;
    for (std::size_t k = 0; k < cols; ++k) w += q[k][i] * z[k];
    weights[i] = static_cast<double>(factor * w);
  }
  return weights;
}

double power_of(double delta, int k) {
  double p = 1;
  for (int i = 0; i < k; ++i) p *= delta;
  return p;
}

double dot(const std::vector<double>& weights, const double* y) {
  double sum = 0;
  for (std::size_t i = 0; i < weights.size(); ++i) sum += weights[i] * y[i];
  return sum;
}

// One pass of a moving arc with `derivative`, valid on [lo, hi) of `in`; returns the new valid range.
std::pair<std::size_t, std::size_t> apply_pass(const std::vector<double>& in, std::vector<double>& out,
                                               std::size_t lo, std::size_t hi, int derivative, double delta,
                                               const DerivativeOptions& options) {
  const int window = options.window;
  const auto h = static_cast<std::size_t>(window / 2);
  const std::size_t n = in.size();
  out.assign(n, kNaN);
  SavitzkyGolaySpec spec{window, options.polyorder, derivative, -1, delta};
  if (options.edges == DerivativeOptions::Edges::drop) {
    if (hi - lo < static_cast<std::size_t>(window)) return {lo, lo};  // nothing has a full neighbourhood
    const auto centre = std::get<std::vector<double>>(savitzky_golay_weights(spec));
    for (std::size_t i = lo + h; i + h < hi; ++i) out[i] = dot(centre, &in[i - h]);
    return {lo + h, hi - h};
  }
  // shorten: the caller has checked n >= window; samples near an end use the first or last full
  // window with the evaluation point moved off centre.
  std::vector<std::vector<double>> by_position(static_cast<std::size_t>(window));
  for (int p = 0; p < window; ++p) {
    spec.position = p;
    by_position[static_cast<std::size_t>(p)] = std::get<std::vector<double>>(savitzky_golay_weights(spec));
  }
  const std::size_t last_start = n - static_cast<std::size_t>(window);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t start = i < h ? 0 : std::min(i - h, last_start);
    out[i] = dot(by_position[i - start], &in[start]);
  }
  return {0, n};
}

}  // namespace

bool SavitzkyGolaySpec::is_valid(std::string* why) const {
  auto fail = [&](std::string reason) {
    if (why) *why = std::move(reason);
    return false;
  };
  if (window < 1 || window % 2 == 0) return fail("the window must be an odd number of samples");
  if (window > 1001) return fail("the window must be at most 1001 samples");
  if (polyorder < 0 || polyorder >= window) return fail("the polynomial order must be at least 0 and below the window");
  if (derivative < 0 || derivative > polyorder)
    return fail("the derivative order must be at least 0 and at most the polynomial order");
  if (position < -1 || position >= window) return fail("the evaluation position must lie inside the window");
  if (!(delta > 0) || !std::isfinite(delta)) return fail("the sample spacing must be a positive number");
  return true;
}

std::variant<std::vector<double>, Diagnostic> savitzky_golay_weights(const SavitzkyGolaySpec& spec) {
  if (std::string why; !spec.is_valid(&why)) return data_diag::invalid_signal_options("a moving arc", why);
  const int position = spec.position < 0 ? spec.window / 2 : spec.position;
  std::vector<double> weights = unit_spacing_weights(spec.window, spec.polyorder, spec.derivative, position);
  const double scale = power_of(spec.delta, spec.derivative);
  if (scale != 1)
    for (double& w : weights) w /= scale;
  return weights;
}

std::vector<double> IntegerStencil::weights(double delta) const {
  const double scale = static_cast<double>(divisor) * power_of(delta, derivative);
  std::vector<double> out;
  out.reserve(numerators.size());
  for (long long c : numerators) out.push_back(static_cast<double>(c) / scale);
  return out;
}

namespace thesis_stencil {
// eq. 3-1.2: A = (1/35)[17 y_n + 12(y_{n+1} + y_{n-1}) - 3(y_{n+2} + y_{n-2})]
IntegerStencil smooth_5_quadratic() { return {0, 35, {-3, 12, 17, 12, -3}}; }
// eq. 3-1.3: B = (1/(10 Delta))[2 y_{n+2} + y_{n+1} - y_{n-1} - 2 y_{n-2}]
IntegerStencil first_5_quadratic() { return {1, 10, {-2, -1, 0, 1, 2}}; }
// eq. 3-1.5: (1/(100 Delta^2))[4(y_{n+-4}) + 4(y_{n+-3}) + (y_{n+-2}) - 4(y_{n+-1}) - 10 y_n]
IntegerStencil second_5_repeated() { return {2, 100, {4, 4, 1, -4, -10, -4, 1, 4, 4}}; }
// eq. 3-1.6: (1/21)[7 y_n + 6(y_{n+-1}) + 3(y_{n+-2}) - 2(y_{n+-3})]
IntegerStencil smooth_7_cubic() { return {0, 21, {-2, 3, 6, 7, 6, 3, -2}}; }
// eq. 3-1.7: (1/(252 Delta))[58(y_{n+1} - y_{n-1}) + 67(y_{n+2} - y_{n-2}) - 22(y_{n+3} - y_{n-3})]
IntegerStencil first_7_cubic() { return {1, 252, {22, -67, -58, 0, 58, 67, -22}}; }
// eq. 3-1.8: (1/(252 Delta)^2)[484(y_{n+-6}) - 2948(y_{n+-5}) + 1937(y_{n+-4}) + 7772(y_{n+-3})
//            + 5916(y_{n+-2}) - 4824(y_{n+-1}) - 16674 y_n]
IntegerStencil second_7_repeated() {
  return {2, 252 * 252, {484, -2948, 1937, 7772, 5916, -4824, -16674, -4824, 5916, 7772, 1937, -2948, 484}};
}
}  // namespace thesis_stencil

std::vector<double> compose_stencils(std::span<const double> first, std::span<const double> second) {
  if (first.empty() || second.empty()) return {};
  std::vector<double> out(first.size() + second.size() - 1, 0.0);
  for (std::size_t i = 0; i < first.size(); ++i)
    for (std::size_t j = 0; j < second.size(); ++j) out[i + j] += first[i] * second[j];
  return out;
}

bool DerivativeOptions::is_valid(std::string* why) const {
  SavitzkyGolaySpec spec;
  spec.window = window;
  spec.polyorder = polyorder;
  if (!spec.is_valid(why)) return false;
  if (second == Second::repeated && polyorder < 1) {
    if (why) *why = "repeated differentiation needs a polynomial order of at least 1";
    return false;
  }
  return true;
}

int samples_lost_each_side(int order, const DerivativeOptions& options) {
  if (order < 0 || !options.is_valid()) return -1;
  if (options.edges == DerivativeOptions::Edges::shorten) return 0;
  const int h = options.window / 2;
  const bool repeated = options.second == DerivativeOptions::Second::repeated && order >= 1;
  return repeated ? order * h : h;  // thesis 4-1: tau0 = 3 alpha Delta for the 7-point operators
}

std::variant<std::vector<double>, Diagnostic> estimate_derivative(std::span<const double> samples, double delta,
                                                                  int order, const DerivativeOptions& options) {
  const char* operation = "a derivative estimate";
  if (std::string why; !options.is_valid(&why)) return data_diag::invalid_signal_options(operation, why);
  if (order < 0) return data_diag::invalid_signal_options(operation, "the derivative order must be at least 0");
  if (!(delta > 0) || !std::isfinite(delta))
    return data_diag::invalid_signal_options(operation, "the sample spacing must be a positive number");
  const bool repeated = options.second == DerivativeOptions::Second::repeated && order >= 1;
  if (!repeated && order > options.polyorder)
    return data_diag::invalid_signal_options(
        operation, fmt::format("a direct derivative of order {} needs a polynomial order of at least {}", order, order));
  if (repeated && order > 64) return data_diag::invalid_signal_options(operation, "the derivative order is above 64");
  if (options.edges == DerivativeOptions::Edges::shorten && samples.size() < static_cast<std::size_t>(options.window))
    return data_diag::signal_shorter_than_window(samples.size(), options.window);

  std::vector<double> current(samples.begin(), samples.end());
  std::vector<double> next;
  std::size_t lo = 0;
  std::size_t hi = current.size();
  const int passes = repeated ? order : 1;
  const int derivative_per_pass = repeated ? 1 : order;
  for (int pass = 0; pass < passes; ++pass) {
    std::tie(lo, hi) = apply_pass(current, next, lo, hi, derivative_per_pass, delta, options);
    current.swap(next);
  }
  return current;
}

std::string MovingArcOperator::name() const {
  const bool several = order_ >= 2;
  return fmt::format("{}-point moving arc of order {}, {}{}{}", options_.window, options_.polyorder,
                     order_ == 0 ? std::string("smoothing") : fmt::format("derivative {}", order_),
                     several ? (options_.second == DerivativeOptions::Second::repeated ? " (repeated)" : " (direct)") : "",
                     options_.edges == DerivativeOptions::Edges::shorten ? ", edges shortened" : "");
}

int MovingArcOperator::samples_lost_each_side() const { return sidc::samples_lost_each_side(order_, options_); }

std::optional<std::size_t> MovingArcOperator::reach() const {
  const auto h = static_cast<std::size_t>(options_.window / 2);
  const bool repeated = options_.second == DerivativeOptions::Second::repeated && order_ >= 1;
  return (repeated ? static_cast<std::size_t>(order_) * h : h) + static_cast<std::size_t>(options_.window);
}

std::variant<std::vector<double>, Diagnostic> MovingArcOperator::apply(std::span<const double> samples, double step) const {
  return estimate_derivative(samples, step, order_, options_);
}

}  // namespace sidc
