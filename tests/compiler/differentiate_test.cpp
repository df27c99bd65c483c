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

}  // namespace
}  // namespace sidc
