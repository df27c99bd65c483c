// A model's plot statement, compiled from text and drawn with known parameter values: the values
// must be the function written, at both ends and across a guard's switch.
#include <gtest/gtest.h>

#include <cmath>

#include "compiler/pipeline.hpp"
#include "runtime/operators/plot_function.hpp"

namespace sidc {
namespace {

ir::Model compiled(const std::string& text) {
  const CompileResult r = compile(std::make_shared<const SourceFile>("plot.sid", text), {});
  EXPECT_FALSE(r.diagnostics.has_errors()) << r.diagnostics.render_all();
  return r.normalized.value_or(ir::Model{});
}

TEST(PlotFunction, DrawsTheFittedFunctionAndItsTruth) {
  const ir::Model m = compiled(
      "input x\noutput y\nparam m, c1, c3, k\n"
      "m*y'' + c1*y' + c3*y'^3*[y' >= 0] + k*y = x\n"
      "plot damper(y') = c1*y' + c3*y'^3*[y' >= 0] against 0.5*y' + 1\n");
  ASSERT_EQ(m.plots.size(), 1u);
  const std::vector<double> values{1.0, 2.0, 3.0, 4.0};  // m, c1, c3, k
  auto result = evaluate_plot_function(m.plots[0], values, -1.0, 2.0, 4);
  ASSERT_TRUE(std::holds_alternative<PlotCurve>(result)) << render(std::get<Diagnostic>(result));
  const PlotCurve& c = std::get<PlotCurve>(result);
  EXPECT_EQ(c.argument, "y'");
  ASSERT_EQ(c.x.size(), 4u);
  const std::vector<double> x{-1, 0, 1, 2};
  for (std::size_t i = 0; i < x.size(); ++i) {
    EXPECT_DOUBLE_EQ(c.x[i], x[i]);
    const double expected = 2 * x[i] + (x[i] >= 0 ? 3 * x[i] * x[i] * x[i] : 0.0);
    EXPECT_DOUBLE_EQ(c.fitted[i], expected) << "at y' = " << x[i];
    EXPECT_DOUBLE_EQ(c.truth[i], 0.5 * x[i] + 1) << "at y' = " << x[i];
  }
}

TEST(PlotFunction, ParameterFreeTermsAreDrawnAndNoTruthMeansNoCurve) {
  const ir::Model m = compiled("input x\noutput y\nk1*y + k3*y^3 + y' = x\nplot spring(y) = k1*y + k3*y^3 + 2*y\n");
  ASSERT_EQ(m.plots.size(), 1u);
  const int k1 = m.parameter_index("k1"), k3 = m.parameter_index("k3");
  std::vector<double> values(m.parameters.size(), 0.0);
  values[static_cast<std::size_t>(k1)] = -1;
  values[static_cast<std::size_t>(k3)] = 0.25;
  auto result = evaluate_plot_function(m.plots[0], values, -2, 2, 5);
  ASSERT_TRUE(std::holds_alternative<PlotCurve>(result));
  const PlotCurve& c = std::get<PlotCurve>(result);
  EXPECT_TRUE(c.truth.empty());
  for (std::size_t i = 0; i < c.x.size(); ++i) EXPECT_DOUBLE_EQ(c.fitted[i], -c.x[i] + 0.25 * std::pow(c.x[i], 3) + 2 * c.x[i]);
}

}  // namespace
}  // namespace sidc
