// Moving-arc (Savitzky–Golay) smoothing and differentiation of uniformly sampled signals,
// thesis section 3-1: fit a low-order polynomial by least squares to the samples around t_n and
// take the polynomial's value or derivative at t_n.
//
// Relies on: <cmath> alone for the numerics (a Gram-Schmidt QR in long double); signal_operator.hpp
// for the interface MovingArcOperator presents to the evaluators. Guarantees: weights are derived in code
// for any odd window, any polynomial order < window, any derivative order <= polynomial order,
// any evaluation position inside the window (off-centre weights serve the edges), and any
// spacing delta, agreeing with the exact rational weights to about 1e-15 relative (tested against
// tests/runtime/data/central_coefficients.csv and scipy_examples.csv). Nothing throws or aborts:
// invalid options come back as a Diagnostic without a location (the caller adds the span of the
// model term that asked for the derivative).
//
// Conventions: weights are in correlation ("dot") order, w[0] multiplies the earliest sample of
// the window, so an estimate is sum_i w[i] * y[first + i]. A derivative of order k is in units
// of y per delta^k.
#pragma once

#include <span>
#include <string>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "runtime/operators/signal_operator.hpp"

namespace sidc {

struct SavitzkyGolaySpec {
  int window = 7;       // odd, >= 1
  int polyorder = 3;    // 0 <= polyorder < window
  int derivative = 0;   // 0 <= derivative <= polyorder (0 = smoothing)
  int position = -1;    // 0-based evaluation index in the window; -1 = the centre
  double delta = 1.0;   // sample spacing, > 0

  bool is_valid(std::string* why = nullptr) const;
};

// The least-squares weights of `spec`, dot order, already divided by delta^derivative.
std::variant<std::vector<double>, Diagnostic> savitzky_golay_weights(const SavitzkyGolaySpec& spec);

// A centred stencil with integer weights as the thesis prints them:
// estimate_n = (1 / (divisor * delta^derivative)) * sum_i numerators[i] * y[n - h + i].
struct IntegerStencil {
  int derivative = 0;
  long long divisor = 1;
  std::vector<long long> numerators;  // dot order, odd length 2h + 1

  int half_width() const { return static_cast<int>(numerators.size() / 2); }
  std::vector<double> weights(double delta) const;
};

// The formulas of thesis section 3-1, typed from the thesis (the tests derive each one
// independently and compare).
namespace thesis_stencil {
IntegerStencil smooth_5_quadratic();  // eq. 3-1.2: A of y = A + B tau + C tau^2 over 5 points
IntegerStencil first_5_quadratic();   // eq. 3-1.3: B, the 5-point first derivative
IntegerStencil second_5_repeated();   // eq. 3-1.5: eq. 3-1.3 applied twice (eq. 3-1.4), expanded
IntegerStencil smooth_7_cubic();      // eq. 3-1.6: cubic over 7 points, value at the centre
IntegerStencil first_7_cubic();       // eq. 3-1.7: cubic over 7 points, first derivative
IntegerStencil second_7_repeated();   // eq. 3-1.8: eq. 3-1.7 applied twice, expanded
}  // namespace thesis_stencil

// The weights of applying centred stencil `first` and then centred stencil `second` (a
// convolution); how eq. 3-1.5 follows from eq. 3-1.3 and eq. 3-1.8 from eq. 3-1.7.
std::vector<double> compose_stencils(std::span<const double> first, std::span<const double> second);

struct DerivativeOptions {
  int window = 7;     // eqs. 3-1.6 .. 3-1.8: a cubic through 7 points, as the thesis uses in 4-1
  int polyorder = 3;
  // Orders >= 2: `repeated` applies the first-derivative operator k times (eqs. 3-1.4, 3-1.5,
  // 3-1.8, the thesis' choice); `direct` differentiates the fitted polynomial k times (needs
  // k <= polyorder). Order 0 is smoothing and order 1 the same in both.
  enum class Second { repeated, direct } second = Second::repeated;
  // `drop`: a sample without its full neighbourhood has no estimate (NaN), so the first usable
  // sample of a k-th repeated derivative is k * (window - 1) / 2 in (thesis 4-1: tau0 = 3 alpha
  // Delta for 7 points). `shorten`: the edge samples use the off-centre weights of the first or
  // last full window, so every sample has an estimate.
  enum class Edges { drop, shorten } edges = Edges::drop;

  bool is_valid(std::string* why = nullptr) const;
};

// How many samples at each end estimate_derivative(order) leaves without a value (NaN). Order 0
// means smoothing, which loses (window - 1) / 2 under `drop`; a signal used as it is, unsmoothed,
// loses nothing and should not be counted. Returns 0 under `shorten`, -1 for invalid input.
int samples_lost_each_side(int order, const DerivativeOptions& options);

// The order-th derivative estimate of `samples` (uniform spacing delta) at every sample: order 0
// smooths, 1 and 2 are eqs. 3-1.3/3-1.7 and 3-1.5/3-1.8 for the matching windows; higher orders
// follow `second`. NaN where `drop` leaves no value. Errors: invalid options, order < 0, delta
// not positive, order > polyorder under `direct`, fewer samples than the window under `shorten`.
std::variant<std::vector<double>, Diagnostic> estimate_derivative(std::span<const double> samples, double delta,
                                                                  int order, const DerivativeOptions& options);

// estimate_derivative() of one order as a SignalOperator, what the evaluators call.
class MovingArcOperator final : public SignalOperator {
 public:
  MovingArcOperator(int order, const DerivativeOptions& options) : order_(order), options_(options) {}
  std::string name() const override;
  int samples_lost_each_side() const override;
  // What `drop` loses, plus one window: `shorten` moves the stencils off centre near the ends of
  // whatever it is given, and that must only touch the margin.
  std::optional<std::size_t> reach() const override;
  std::variant<std::vector<double>, Diagnostic> apply(std::span<const double> samples, double step) const override;

 private:
  int order_;
  DerivativeOptions options_;
};

}  // namespace sidc
