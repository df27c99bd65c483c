// The weak form's integrals across a switch (runtime/solve/switch_quadrature.hpp).
//
// What each check proves:
// - Which terms are corrected: one sign() or one single-condition guard that makes the term jump;
//   not a term that is continuous at its switch (y' * [y' > 0], y'^2 * sign(y')), not sign()^2,
//   not two switches, not a guard of two conditions.
// - The rows of sign(x) and [x > 0.5] against phi_j, x = sin(1.7 t + 0.3) sampled every 0.05, are
//   the integrals with the switches where x crosses (known in closed form) to 1e-3 of phi's
//   integral and 20 times closer than the trapezoid over the samples alone, which is off by more
//   than 5e-3 on some row: a wrong interval, fraction theta, sign of the jump or row offset would
//   leave errors of the trapezoid's size.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "compiler/pipeline.hpp"
#include "ir/print.hpp"
#include "runtime/operators/test_functions.hpp"
#include "runtime/solve/switch_quadrature.hpp"
#include "runtime/solve/weak_design.hpp"

namespace sidc {
namespace {

ir::Model compiled(const std::string& text) {
  CompileResult c = compile(std::make_shared<const SourceFile>("switch.sid", text), {});
  EXPECT_TRUE(c.ok()) << c.diagnostics.render_all();
  return c.ok() ? *c.integrated : ir::Model{};
}

TEST(SwitchQuadrature, CorrectsTermsThatJumpAtOneSwitch) {
  const ir::Model model = compiled(
      "input x\noutput y\nparam a, b, c, d, e, f, g, h\nset form = weak\n"
      "a*y' + b*sign(y') + c*[x > 0.5]*y + d*y'*[y' > 0] + e*y'^2*sign(y') + f*sign(y')^2 + g*sign(x)*[y > 0] + h*[x > 0 and y < 1] = x\n");
  std::vector<std::string> corrected;
  for (const auto& term : model.equations.at(0).terms)
    for (const auto& [k, part] : parts_by_test_function(term.operation))
      for (const auto& s : switched_terms(part)) corrected.push_back(print(s.jump) + " times " + print(s.rest));
  std::sort(corrected.begin(), corrected.end());
  ASSERT_EQ(corrected.size(), 2u);
  EXPECT_EQ(corrected[0], "[x > 1/2] times y");
  EXPECT_EQ(corrected[1], "sign(y') times 1");
}

// int over [lo, hi] of phi_j(t) * (switch value), phi_j = (1 - s^2)^p, by Simpson's rule on pieces
// between the switch times (each piece smooth: a polynomial of degree 2p, integrated to 1e-12).
double exact_row(double centre, double half, int p, const std::vector<double>& switches, double (*value_at)(double)) {
  std::vector<double> cuts{centre - half};
  for (double s : switches)
    if (s > centre - half && s < centre + half) cuts.push_back(s);
  cuts.push_back(centre + half);
  double total = 0;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double a = cuts[i], b = cuts[i + 1], v = value_at(0.5 * (a + b));
    const int n = 2000;
    const double h = (b - a) / n;
    double piece = 0;
    for (int k = 0; k <= n; ++k) {
      const double s = (a + k * h - centre) / half, phi = std::pow(1 - s * s, p);
      piece += (k == 0 || k == n ? 1 : k % 2 ? 4 : 2) * phi;
    }
    total += v * piece * h / 3;
  }
  return total;
}

double x_of(double t) { return std::sin(1.7 * t + 0.3); }
double sign_of_x(double t) { return x_of(t) > 0 ? 1.0 : -1.0; }
double above_half(double t) { return x_of(t) > 0.5 ? 1.0 : 0.0; }

TEST(SwitchQuadrature, RowsIntegrateTheSwitchWhereItsArgumentCrosses) {
  const double step = 0.05;
  const std::size_t n = 801;  // t = 0 to 40: 21 zero crossings of x, 21 crossings of 0.5
  SampledRecord record;
  record.path = "switch.csv";
  record.step = step;
  std::vector<double> t(n), x(n), y(n);
  for (std::size_t i = 0; i < n; ++i) t[i] = static_cast<double>(i) * step, x[i] = x_of(t[i]), y[i] = std::cos(t[i]);
  record.time = t;
  record.signals["x"] = x;
  record.signals["y"] = y;
  const ir::Model model = compiled("input x\noutput y\nparam a, f, g\nset form = weak\na*y' + f*sign(x) + g*[x > 0.5] = x\n");
  TestFunctionGrid grid;
  grid.half_width = 30;
  grid.degree = 10;
  for (std::size_t c = 30; c + 30 < n; c += 7) grid.centres.push_back(c);
  // Switch times: 1.7 t + 0.3 = k pi (x = 0) and pi/6, 5 pi/6 + 2 k pi (x = 0.5).
  std::vector<double> zeros, halves;
  for (int k = 0; k < 30; ++k) {
    zeros.push_back((k * std::numbers::pi - 0.3) / 1.7);
    halves.push_back((std::numbers::pi / 6 + 2 * k * std::numbers::pi - 0.3) / 1.7);
    halves.push_back((5 * std::numbers::pi / 6 + 2 * k * std::numbers::pi - 0.3) / 1.7);
  }
  const double half = static_cast<double>(grid.half_width) * step;
  const double phi_integral = exact_row(0, half, grid.degree, {}, [](double) { return 1.0; });
  const std::vector<double> w = test_function_weights(grid, 0, step);
  const FitWindow window{0, n - 1};
  Evaluator evaluator(record, model, EvaluationOptions{}, window);
  WeakValues weak(evaluator, grid);
  int checked = 0;
  for (const auto& term : model.equations.at(0).terms) {
    const std::string printed = print(term.operation);
    const bool is_sign = printed.find("sign") != std::string::npos, is_guard = printed.find('[') != std::string::npos;
    if (!is_sign && !is_guard) continue;
    std::vector<double> rows(grid.centres.size());
    ASSERT_FALSE(weak.evaluate(term.operation, 0, printed, rows).has_value());
    double worst = 0, worst_trapezoid = 0;
    for (std::size_t j = 0; j < rows.size(); ++j) {
      const double centre = t[grid.centres[j]];
      const double exact = exact_row(centre, half, grid.degree, is_sign ? zeros : halves, is_sign ? sign_of_x : above_half);
      double trapezoid = 0;
      for (std::size_t i = 0; i < w.size(); ++i) trapezoid += w[i] * (is_sign ? sign_of_x : above_half)(t[grid.centres[j] - grid.half_width + i]);
      worst = std::max(worst, std::abs(rows[j] - exact) / phi_integral);
      worst_trapezoid = std::max(worst_trapezoid, std::abs(trapezoid - exact) / phi_integral);
    }
    // Linear interpolation puts the switch within h^2/8 |x''/x'| of its time: 3e-4 where x = 0.5.
    EXPECT_LT(worst, 1e-3) << printed;
    EXPECT_LT(worst, worst_trapezoid / 20) << printed;
    EXPECT_GT(worst_trapezoid, 5e-3) << printed;
    ++checked;
  }
  EXPECT_EQ(checked, 2);
}

}  // namespace
}  // namespace sidc
