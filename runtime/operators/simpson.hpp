// Cumulative integration of uniformly sampled signals (thesis section 3-2: "the well known
// Simpson formula which determines the area under the second order polynomial uniquely fitted to
// three points"), optionally after moving-arc smoothing ("it is advisable to first smooth the
// data before actually performing the integration").
//
// Relies on: savitzky_golay.hpp for the optional smoothing, signal_operator.hpp for the interface
// CumulativeIntegralOperator presents to the evaluators. Guarantees: I[0] = 0 and I[i] is the
// integral from sample 0 to sample i, at every i; nested integrals are repeated application.
//
// cumulative_simpson, exactly:
//   even i:  I[i] = I[i-2] + h/3 (f[i-2] + 4 f[i-1] + f[i])                 composite Simpson
//   odd i:   I[i] = I[i-1] + one interval [i-1, i] from the cubic through four neighbouring samples:
//              i >= 3:  h/24 (f[i-3] - 5 f[i-2] + 19 f[i-1] + 9 f[i])
//              i == 1:  h/24 (9 f[0] + 19 f[1] - 5 f[2] + f[3])
//   The even samples never depend on the odd ones, so each odd value carries one single-interval
//   term on top of a pure composite-Simpson value. Both rules are exact for cubics, so I is exact
//   for cubic f at every i (Simpson's own degree of exactness, even and odd alike) and converges
//   at 4th order. With exactly 3 samples the single interval uses the parabola: h/12 (5 f[0] +
//   8 f[1] - f[2]); with 2 samples, the trapezoid.
#pragma once

#include <span>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "runtime/operators/savitzky_golay.hpp"
#include "runtime/operators/signal_operator.hpp"

namespace sidc {

std::vector<double> cumulative_simpson(std::span<const double> values, double delta);

// I[i] = I[i-1] + h/2 (f[i-1] + f[i]): exact for straight lines, 2nd order.
std::vector<double> cumulative_trapezoid(std::span<const double> values, double delta);

struct IntegrationOptions {
  enum class Rule { simpson, trapezoid } rule = Rule::simpson;
  // Moving-arc smoothing before integrating: window 0 = none. Edges are always `shorten` here,
  // since the integral starts at sample 0 and every sample must have a value.
  int smoothing_window = 0;
  int smoothing_polyorder = 3;

  bool is_valid(std::string* why = nullptr) const;
};

// Smooths (when asked) and integrates cumulatively. Errors: invalid options, delta not positive,
// fewer samples than the smoothing window.
std::variant<std::vector<double>, Diagnostic> cumulative_integral(std::span<const double> values, double delta,
                                                                  const IntegrationOptions& options = {});

// cumulative_integral() as a SignalOperator, what the evaluators call. Every sample has a value,
// and every value depends on all the samples before it (reach() is nullopt).
class CumulativeIntegralOperator final : public SignalOperator {
 public:
  explicit CumulativeIntegralOperator(const IntegrationOptions& options) : options_(options) {}
  std::string name() const override;
  int samples_lost_each_side() const override { return 0; }
  std::optional<std::size_t> reach() const override { return std::nullopt; }
  std::variant<std::vector<double>, Diagnostic> apply(std::span<const double> samples, double step) const override;

 private:
  IntegrationOptions options_;
};

}  // namespace sidc
