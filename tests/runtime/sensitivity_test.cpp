// The sensitivity equations of runtime/simulate/simulate (SimulateOptions::sensitivities): under
// RK4 they are the exact derivatives of the discrete run, so they must agree with central finite
// differences of whole runs to the differences' own error, for every parameter and every
// initial-state component, on a nonlinear single output, a coefficient of y'' that depends on the
// state, a coupled two-output system and a held input.
#include <cmath>
#include <gtest/gtest.h>

#include "compiler/pipeline.hpp"
#include "runtime/simulate/simulate.hpp"
#include "support/simulation.hpp"

namespace sidc {
namespace {

using testing::form_of;
using testing::grid;
using testing::normalized;


SimulationSummary solved(const ir::Model& m, const ExplicitForm& f, const SimulateOptions& o) {
  auto r = simulate(m, f, o);
  EXPECT_TRUE(std::holds_alternative<SimulationSummary>(r)) << render(std::get<Diagnostic>(r));
  return std::get<SimulationSummary>(r);
}

// Every sensitivity column against (solved(q + h) - solved(q - h)) / 2h; returns the largest error
// relative to the column's largest magnitude.
double largest_sensitivity_error(const ir::Model& m, const SimulateOptions& base) {
  const ExplicitForm f = form_of(m);
  SimulateOptions o = base;
  o.sensitivities = true;
  const SimulationSummary exact = solved(m, f, o);
  EXPECT_TRUE(exact.completed()) << exact.message;
  const std::size_t columns = exact.sensitivity_columns;
  EXPECT_EQ(columns, m.parameters.size() + f.state_size());
  std::vector<std::pair<std::string, int>> state;  // initial-state components in column order
  for (const auto& out : f.outputs)
    for (int k = 0; k < out.order; ++k) state.emplace_back(out.name, k);
  double worst = 0;
  for (std::size_t q = 0; q < columns; ++q) {
    auto shifted = [&](double h) {
      SimulateOptions p = base;
      if (q < m.parameters.size()) p.parameters[q] += h;
      else p.initial[state[q - m.parameters.size()].first][static_cast<std::size_t>(state[q - m.parameters.size()].second)] += h;
      return solved(m, f, p);
    };
    const double h = 1e-6;
    const SimulationSummary up = shifted(h), down = shifted(-h);
    for (std::size_t j = 0; j < f.outputs.size(); ++j) {
      double scale = 1e-12, error = 0;
      for (std::size_t row = 0; row < o.time.size(); ++row) {
        const double s = exact.sensitivity[j][row * columns + q];
        const double fd = (up.outputs[j][row] - down.outputs[j][row]) / (2 * h);
        scale = std::max(scale, std::abs(fd));
        error = std::max(error, std::abs(s - fd));
      }
      worst = std::max(worst, error / scale);
    }
  }
  return worst;
}

TEST(Sensitivity, DuffingAgreesWithFiniteDifferences) {
  const ir::Model m = normalized("input x = cos(1.2*t)\noutput y\nparam m, c, k, k3\nm*y'' + c*y' + k*y + k3*y^3 = x\n");
  SimulateOptions o;
  o.parameters = {1.0, 0.1, 1.0, 0.5};
  o.initial["y"] = {0.5, -0.2};
  o.time = grid(0, 20, 0.05);
  EXPECT_LT(largest_sensitivity_error(m, o), 1e-6);
}

TEST(Sensitivity, StateDependentCoefficientAndFunctions) {
  const ir::Model m = normalized("input x = sin(t)\noutput y\nparam a, b, c\na*(1 + y^2)*y'' + b*sin(y)*y' + c*tanh(y) = x\n");
  SimulateOptions o;
  o.parameters = {1.0, 0.3, 2.0};
  o.initial["y"] = {0.2, 0.1};
  o.time = grid(0, 10, 0.05);
  EXPECT_LT(largest_sensitivity_error(m, o), 1e-6);
}

TEST(Sensitivity, CoupledOutputs) {
  const ir::Model m = normalized(
      "input u = cos(t)\noutput y1, y2\nparam a, b, c, d, e\n"
      "y1' + a*y1 + b*y1*y2 = u\n"
      "y2'' + c*y2' + d*y2 + e*y1 = 0\n");
  SimulateOptions o;
  o.parameters = {0.5, 0.2, 0.4, 2.0, 1.0};
  o.initial["y1"] = {0.3};
  o.initial["y2"] = {0.0, 0.5};
  o.time = grid(0, 10, 0.05);
  EXPECT_LT(largest_sensitivity_error(m, o), 1e-6);
}

TEST(Sensitivity, HeldInput) {
  const ir::Model m = normalized("input x held\noutput y\nparam a, b\na*y' + b*y = x\n");
  SimulateOptions o;
  o.parameters = {2.0, 1.0};
  o.initial["y"] = {0.1};
  o.time = grid(0, 10, 0.1);
  for (std::size_t i = 0; i < o.time.size(); ++i) o.inputs["x"].push_back(i % 20 < 10 ? 1.0 : -1.0);
  EXPECT_LT(largest_sensitivity_error(m, o), 1e-6);
}

// Nonlinear parameters (`param L = 1.2`): their columns come from the symbolic partial derivative
// by the parameter (ir/differentiate.hpp), in a linear parameter's operation (k*sin(L*y)), in the
// parameter-free side (exp(-r*t)*y) and in the coefficient of y'' (m*(1 + g*y^2)).
TEST(Sensitivity, NonlinearParameters) {
  const ir::Model m = normalized(
      "input x = cos(1.2*t)\noutput y\nparam m, c, k, L = 1, r = 0.5, g = 0.1\n"
      "m*(1 + g*y^2)*y'' + c*y' + k*sin(L*y) + exp(-r*t)*y = x\n");
  ASSERT_TRUE(m.parameters[3].nonlinear && m.parameters[4].nonlinear && m.parameters[5].nonlinear);
  SimulateOptions o;
  o.parameters = {1.0, 0.1, 2.0, 0.8, 0.3, 0.2};
  o.initial["y"] = {0.5, -0.2};
  o.time = grid(0, 20, 0.05);
  EXPECT_LT(largest_sensitivity_error(m, o), 1e-6);
}

// Coulomb friction: the right-hand side jumps at every reversal of y', and the sensitivities jump
// with it (the switch time moves with every parameter); differences of whole runs, whose switches
// are located to 1e-13, see that jump.
TEST(Sensitivity, JumpAtEachSwitchOfSign) {
  const ir::Model m = normalized("input x = 0.5*cos(1.7*t)\noutput y\nparam J, c, f, k\nJ*y'' + c*y' + f*sign(y') + k*sin(y) = x\n");
  ASSERT_EQ(form_of(m).switching_functions.size(), 1u);  // sign(y')'s argument, located like a guard
  SimulateOptions o;
  o.parameters = {1.0, 0.1, 0.05, 2.0};  // swings of about 0.3 rad that never stick
  o.initial["y"] = {0.2, 0.3};  // y'(0) != 0: sign(y') is not differentiable where it starts at 0
  o.time = grid(0, 10, 0.02);
  EXPECT_LT(largest_sensitivity_error(m, o), 1e-5);
}

// A force that switches on where y crosses 0 (a spring with a preload on one side), and a
// stiffness that changes there: the first jumps the right-hand side, the second only its slope.
TEST(Sensitivity, JumpAtEachSwitchOfAGuard) {
  const ir::Model m = normalized("input x = 2*cos(t)\noutput y\nparam a, b, c, d, e\na*y'' + d*y' + b*[y > 0]*y + c*[y <= 0]*y + e*[y > 0] = x\n");
  SimulateOptions o;
  o.parameters = {1.0, 1.0, 4.0, 0.2, 0.3};
  o.initial["y"] = {0.5, 0.0};
  o.time = grid(0, 15, 0.02);
  EXPECT_LT(largest_sensitivity_error(m, o), 1e-5);
}

// A threshold that is a nonlinear parameter (`param y0 = 0.1` in `[y > y0]`, a preload that acts
// beyond a gap; `sign(y' - v0)`): the switch time moves with it, d tau/d y0 = -(g_x S + g_y0)/(g_x f + g_t),
// and the sensitivities jump by that too.
TEST(Sensitivity, JumpAtASwitchWhoseThresholdIsAParameter) {
  const ir::Model m = normalized(
      "input x = 2*cos(t)\noutput y\nparam a, b, d, e, f, y0 = 0.1, v0 = 0.05\n"
      "a*y'' + d*y' + b*y + e*[y > y0] + f*sign(y' - v0) = x\n");
  ASSERT_TRUE(m.parameters[5].nonlinear && m.parameters[6].nonlinear);
  ASSERT_EQ(form_of(m).switching_functions.size(), 2u);
  SimulateOptions o;
  o.parameters = {1.0, 2.0, 0.3, 0.4, 0.05, 0.2, 0.1};
  o.initial["y"] = {0.5, 0.3};
  o.time = grid(0, 15, 0.02);
  EXPECT_LT(largest_sensitivity_error(m, o), 1e-5);
}

}  // namespace
}  // namespace sidc
