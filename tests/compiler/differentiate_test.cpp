#include <gtest/gtest.h>

#include "compile_text.hpp"
#include "ir/differentiate.hpp"
#include "ir/node_budget.hpp"
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

// der() of nested functions grows its terms with every order: within a budget of nodes the
// derivative stops as soon as it is spent (10 nested sin, order 8, took 15 s and 650 MB before),
// and below it gives what the unbounded derivative gives.
TEST(Differentiate, StopsWhenItsNodeBudgetIsSpent) {
  ir::Sum nested = signal("y", 0);
  for (int k = 0; k < 10; ++k) nested = ir::factor(ir::Factor{ir::FactorKind::function, "sin", 0, {}, {}, ir::share(nested), {}});
  ir::NodeBudget budget(ir::kMaxNodesBuilt);
  EXPECT_FALSE(differentiate(nested, 8, budget).has_value());
  EXPECT_TRUE(budget.exceeded());

  ir::NodeBudget enough(ir::kMaxNodesBuilt);
  const auto bounded = differentiate(nested, 2, enough);
  ASSERT_TRUE(bounded.has_value());
  EXPECT_FALSE(enough.exceeded());
  EXPECT_EQ(print(*bounded), print(*differentiate(nested, 2)));
}

// What a node count counts: each term and factor, and a shared argument once per place it stands.
TEST(NodeBudget, CountsSharedArgumentsWhereverTheyStand) {
  const ir::Sum y = signal("y", 0);
  EXPECT_EQ(ir::written_nodes(y), 2u);  // a term and its factor
  const ir::Sum sine = ir::factor(ir::Factor{ir::FactorKind::function, "sin", 0, {}, {}, ir::share(y), {}});
  EXPECT_EQ(ir::written_nodes(sine), 4u);
  const ir::Sum both = ir::multiply(sine, ir::factor(ir::Factor{ir::FactorKind::function, "cos", 0, {}, {}, sine.terms[0].factors[0].first.argument, {}}));
  EXPECT_EQ(ir::written_nodes(both), 7u);  // one term, two factors, y (a term and a factor) inside each
  EXPECT_GT(ir::written_nodes(both, 3), 3u);  // stops past its cap
}

// (y + x + t)^k has C(k + 2, 2) terms: past the limit it is refused before anything is
// multiplied; a sum whose products coincide (y + y^2 + y^3) is expanded as before.
TEST(Raise, PredictsTheMultinomialCountOfIndependentTerms) {
  const ir::Sum three = ir::add(ir::add(signal("y", 0), signal("x", 0)), ir::factor(ir::Factor{ir::FactorKind::time, "", 0, {}, {}, {}, {}}));
  EXPECT_FALSE(raise(three, Number(1000000), 20000).has_value());
  EXPECT_EQ(raise(three, Number(4), 20000)->terms.size(), 15u);
  const ir::Sum dependent = ir::add(ir::add(signal("y", 0), signal("y", 0, 2)), signal("y", 0, 3));
  const auto raised = raise(dependent, Number(300), 20000);
  ASSERT_TRUE(raised.has_value());
  EXPECT_EQ(raised->terms.size(), 601u);  // y^300 ... y^900; the multinomial count would be 45 451
  // A single term is raised at once, as 10 000 multiplications would.
  EXPECT_EQ(print(*raise(ir::scale(signal("y", 1), Number(2)), Number(10))), "1024*y'^10");
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

// By a nonlinear parameter (`param L = 1.2`), signals held constant: the refinement's
// sensitivity to it. Other parameters, signals and t are constants.
TEST(PartialDerivative, ByANonlinearParameter) {
  const auto r = testing::compile_text("input x\noutput y\nparam a, L = 1.2, k = 0.1\na*y'' + sin(L*y) + exp(-k*t)*L*y' = x\n",
                                       {{}, "normalize"});
  ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
  const ir::Sum& known = r.normalized->equations[0].known;
  EXPECT_EQ(print(known), "-L*y'*exp(-k*t) + x - sin(L*y)");
  EXPECT_EQ(print(*partial_derivative_by_parameter(known, 1)), "-y'*exp(-k*t) - y*cos(L*y)");
  EXPECT_EQ(print(*partial_derivative_by_parameter(known, 2)), "L*y'*t*exp(-k*t)");
  EXPECT_TRUE(partial_derivative_by_parameter(known, 0)->empty());
  EXPECT_FALSE(partial_derivative_by_parameter(ir::factor(ir::Factor{ir::FactorKind::integral, "", 0, {}, {}, ir::share(known), {}}), 1));
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
