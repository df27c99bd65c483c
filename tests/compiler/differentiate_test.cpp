#include <gtest/gtest.h>

#include "compile_text.hpp"
#include "ir/differentiate.hpp"
#include "ir/print.hpp"

namespace sidc {
namespace {

ir::Sum signal(const std::string& name, int order, int power = 1) {
  return ir::factor(ir::Factor{ir::FactorKind::signal, name, order, {}, {}, {}, {}}, power);
}

TEST(Differentiate, PowerAndProductRules) {
  EXPECT_EQ(print(*differentiate(signal("y", 0, 3))), "3*y'*y^2");
  EXPECT_EQ(print(*differentiate(ir::multiply(signal("x", 0), signal("y", 0)))), "x'*y + x*y'");
  EXPECT_EQ(print(*differentiate(signal("y", 1), 2)), "y'''");
}

TEST(Differentiate, ChainRuleThroughFunctions) {
  const auto r = testing::compile_text("input x\noutput y\nparam a\na*der(sin(y), 1) = x\n", {{}, "normalize"});
  ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
  EXPECT_EQ(print(r.normalized->equations[0], *r.normalized), "a*y'*cos(y) = x");
}

TEST(Differentiate, GuardsHaveNoSymbolicDerivative) {
  const auto r = testing::compile_text("input x\noutput y\nparam a\na*der([y > 0]*y, 1) = x\n", {{}, "normalize"});
  ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
  EXPECT_EQ(print(r.normalized->equations[0], *r.normalized), "a*der(y*[y > 0], 1) = x");
}

TEST(Differentiate, SumsToNegativePowersStayFactors) {
  const auto r = testing::compile_text("input x\noutput y\nparam a\na*der(1/(1 + y), 1) = x\n", {{}, "normalize"});
  ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
  EXPECT_EQ(print(r.normalized->equations[0], *r.normalized), "-a*y'*(y + 1)^-2 = x");
}

// The Jacobian of a right-hand side: every other signal derivative, t and the parameters constant.
TEST(PartialDerivative, ProductAndPowerRulesHoldOtherSlotsConstant) {
  const ir::Sum s = ir::multiply(signal("y", 1), signal("y", 0, 3));  // y'*y^3
  EXPECT_EQ(print(*partial_derivative(s, "y", 0)), "3*y'*y^2");
  EXPECT_EQ(print(*partial_derivative(s, "y", 1)), "y^3");
  EXPECT_TRUE(partial_derivative(s, "x", 0)->empty());
  EXPECT_TRUE(partial_derivative(s, "y", 2)->empty());
}

TEST(PartialDerivative, ChainRuleGuardsAndSignsAreConstantBetweenSwitches) {
  const auto r = testing::compile_text("input x\noutput y\nparam a, b, c\na*y'' + b*sin(y*y') + c*[y' > 0]*y'*y = x\n", {{}, "normalize"});
  ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
  const auto& terms = r.normalized->equations[0].terms;
  ASSERT_EQ(terms.size(), 3u);
  EXPECT_EQ(print(*partial_derivative(terms[1].operation, "y", 0)), "y'*cos(y'*y)");
  EXPECT_EQ(print(*partial_derivative(terms[1].operation, "y", 1)), "y*cos(y'*y)");
  EXPECT_EQ(print(*partial_derivative(terms[2].operation, "y", 1)), "y*[y' > 0]");
  // sign() is a guard in disguise: 0 between its jumps, where d/dt has no Sum at all.
  const auto sgn = testing::compile_text("input x\noutput y\nparam a, f\na*y' + f*sign(y) = x\n", {{}, "normalize"});
  ASSERT_TRUE(sgn.ok()) << sgn.diagnostics.render_all();
  EXPECT_TRUE(partial_derivative(sgn.normalized->equations[0].terms[1].operation, "y", 0)->empty());
  EXPECT_FALSE(differentiate(sgn.normalized->equations[0].terms[1].operation).has_value());
}

}  // namespace
}  // namespace sidc
