// The AST of every expression construct: precedence, associativity, operands, continuation
// lines. Trees are compared as ast_text prints them (every Expression in parentheses).
#include <gtest/gtest.h>

#include "tests/grammar/parse_text.hpp"

namespace sidc {
namespace {

namespace x3 = boost::spirit::x3;
using testing::parse_text;
using testing::statement_text;

// The right-hand side of `z = <expression>`, printed.
std::string expression_text(const std::string& expression) {
  const std::string printed = statement_text("z = " + expression);
  return printed.rfind("z = ", 0) == 0 ? printed.substr(4) : printed;
}

TEST(ParseExpression, MultiplicationBindsTighterThanAddition) {
  EXPECT_EQ(expression_text("a + b*c"), "(a + (b * c))");
  EXPECT_EQ(expression_text("a*b + c"), "((a * b) + c)");
  EXPECT_EQ(expression_text("(a + b)*c"), "((a + b) * c)");
}

TEST(ParseExpression, OneLevelKeepsItsOperatorsInOrder) {
  EXPECT_EQ(expression_text("a - b + c - d"), "(a - b + c - d)");
  EXPECT_EQ(expression_text("a/b*c/d"), "(a / b * c / d)");
}

TEST(ParseExpression, PowerIsRightAssociative) {
  EXPECT_EQ(expression_text("y^2^3"), "(y ^ (2 ^ 3))");
  EXPECT_EQ(expression_text("(y^2)^3"), "((y ^ 2) ^ 3)");
}

TEST(ParseExpression, PowerHoldsASingleRightOperand) {
  const ParseResult result = parse_text("z = y^2^3");
  const auto& power = testing::statement_as<ast::Equation>(result, 0).rhs;
  ASSERT_EQ(power.rest.size(), 1u);
  EXPECT_EQ(power.rest[0].op, '^');
  const auto& exponent = boost::get<x3::forward_ast<ast::Expression>>(power.rest[0].operand.get()).get();
  ASSERT_EQ(exponent.rest.size(), 1u);
  EXPECT_EQ(exponent.rest[0].op, '^');
}

TEST(ParseExpression, UnaryMinusBindsLooserThanPower) {
  EXPECT_EQ(expression_text("-y^2"), "-(y ^ 2)");
  EXPECT_EQ(expression_text("-y*x"), "(-y * x)");
  EXPECT_EQ(expression_text("y^-1"), "(y ^ -1)");
  EXPECT_EQ(expression_text("2^-y^2"), "(2 ^ -(y ^ 2))");
}

TEST(ParseExpression, SignsNest) {
  EXPECT_EQ(expression_text("- - y"), "--y");
  EXPECT_EQ(expression_text("+y"), "+y");
  EXPECT_EQ(expression_text("x - -y"), "(x - -y)");
  EXPECT_EQ(expression_text("x*-y"), "(x * -y)");
  const ParseResult result = parse_text("z = -y");
  const auto& rhs = testing::statement_as<ast::Equation>(result, 0).rhs;
  const auto& negated = boost::get<x3::forward_ast<ast::Signed>>(rhs.first.get()).get();
  EXPECT_EQ(negated.sign, '-');
}

TEST(ParseExpression, ParenthesesLeaveNoNodeOfTheirOwn) {
  EXPECT_EQ(expression_text("((y))"), "y");
  EXPECT_EQ(expression_text("2*(y)"), "(2 * y)");
  const ParseResult result = parse_text("z = (y)");
  const auto& rhs = testing::statement_as<ast::Equation>(result, 0).rhs;
  EXPECT_TRUE(rhs.rest.empty());
  EXPECT_NO_THROW(boost::get<ast::Variable>(rhs.first.get()));
}

TEST(ParseExpression, NoOperandHoldsAnExpressionWithoutOperators) {
  // a1*y'' is a multiplicative level inside the additive one; y'' itself is a bare Variable.
  const ParseResult result = parse_text("z = a1*y'' + y");
  const auto& sum = testing::statement_as<ast::Equation>(result, 0).rhs;
  ASSERT_EQ(sum.rest.size(), 1u);
  const auto& product = boost::get<x3::forward_ast<ast::Expression>>(sum.first.get()).get();
  ASSERT_EQ(product.rest.size(), 1u);
  EXPECT_EQ(product.rest[0].op, '*');
  EXPECT_EQ(boost::get<ast::Variable>(product.rest[0].operand.get()).primes, "''");
  EXPECT_EQ(boost::get<ast::Variable>(sum.rest[0].operand.get()).name.name, "y");
}

TEST(ParseExpression, NumbersKeepTheirText) {
  for (const std::string number : {"3", "0.005", ".5", "5.", "1e-3", "2.5E+4", "007", "1.5e10"}) {
    const ParseResult result = parse_text("z = " + number);
    ASSERT_FALSE(result.diagnostics.has_errors()) << number << "\n" << result.diagnostics.render_all();
    const auto& rhs = testing::statement_as<ast::Equation>(result, 0).rhs;
    EXPECT_EQ(boost::get<ast::Number>(rhs.first.get()).text, number);
  }
}

TEST(ParseExpression, ExponentSignBelongsToTheNumber) {
  EXPECT_EQ(expression_text("1e-3 - 2"), "(1e-3 - 2)");
  EXPECT_EQ(expression_text("y^1e-1^2"), "(y ^ (1e-1 ^ 2))");
}

TEST(ParseExpression, VariablesCarryTheirPrimes) {
  const ParseResult result = parse_text("z = y''' + x_2'");
  const auto& rhs = testing::statement_as<ast::Equation>(result, 0).rhs;
  const auto& first = boost::get<ast::Variable>(rhs.first.get());
  EXPECT_EQ(first.name.name, "y");
  EXPECT_EQ(first.primes, "'''");
  const auto& second = boost::get<ast::Variable>(rhs.rest[0].operand.get());
  EXPECT_EQ(second.name.name, "x_2");
  EXPECT_EQ(second.primes, "'");
}

TEST(ParseExpression, BuiltinNamesAreOrdinaryIdentifiers) {
  EXPECT_EQ(expression_text("t + t0 + tau + pi + e"), "(t + t0 + tau + pi + e)");
  EXPECT_EQ(expression_text("sin(4*pi*t)"), "sin((4 * pi * t))");
}

TEST(ParseExpression, Calls) {
  EXPECT_EQ(expression_text("sin(y)"), "sin(y)");
  EXPECT_EQ(expression_text("der(y^3, 1)"), "der((y ^ 3), 1)");
  EXPECT_EQ(expression_text("int(y)"), "int(y)");
  EXPECT_EQ(expression_text("exp (-y)"), "exp(-y)");
  EXPECT_EQ(expression_text("f(a, b, c + 1)"), "f(a, b, (c + 1))");
}

TEST(ParseExpression, InitialValuesAreCallsOfPrimedNames) {
  const ParseResult result = parse_text("y'(0) = y(0)");
  const auto& equation = testing::statement_as<ast::Equation>(result, 0);
  const auto& lhs = boost::get<x3::forward_ast<ast::Call>>(equation.lhs.first.get()).get();
  EXPECT_EQ(lhs.callee.name.name, "y");
  EXPECT_EQ(lhs.callee.primes, "'");
  ASSERT_EQ(lhs.arguments.size(), 1u);
  EXPECT_EQ(boost::get<ast::Number>(lhs.arguments[0].first.get()).text, "0");
  const auto& rhs = boost::get<x3::forward_ast<ast::Call>>(equation.rhs.first.get()).get();
  EXPECT_EQ(rhs.callee.primes, "");
}

TEST(ParseExpression, FamilyMembers) {
  EXPECT_EQ(expression_text("c[3]"), "c[3]");
  EXPECT_EQ(expression_text("c[k + 6]*y"), "(c[(k + 6)] * y)");
  EXPECT_EQ(expression_text("c [2]"), "c[2]");
  const ParseResult result = parse_text("z = c[k]");
  const auto& member = boost::get<x3::forward_ast<ast::Indexed>>(testing::statement_as<ast::Equation>(result, 0).rhs.first.get()).get();
  EXPECT_EQ(member.name.name, "c");
  EXPECT_EQ(boost::get<ast::Variable>(member.index.first.get()).name.name, "k");
}

TEST(ParseExpression, Guards) {
  EXPECT_EQ(expression_text("[y' <= 0]"), "[y' <= 0]");
  EXPECT_EQ(expression_text("[y >= 0]"), "[y >= 0]");
  EXPECT_EQ(expression_text("[y < 1]"), "[y < 1]");
  EXPECT_EQ(expression_text("[y > -2 and y' < 16]*y"), "([y > -2 and y' < 16] * y)");
  const ParseResult result = parse_text("z = [a + 1 <= b*2 and c > d]");
  const auto& guard = boost::get<x3::forward_ast<ast::Guard>>(testing::statement_as<ast::Equation>(result, 0).rhs.first.get()).get();
  ASSERT_EQ(guard.conditions.size(), 2u);
  EXPECT_EQ(guard.conditions[0].op, "<=");
  EXPECT_EQ(ast_text::text(guard.conditions[0].lhs), "(a + 1)");
  EXPECT_EQ(ast_text::text(guard.conditions[0].rhs), "(b * 2)");
  EXPECT_EQ(guard.conditions[1].op, ">");
}

TEST(ParseExpression, Sums) {
  EXPECT_EQ(expression_text("sum(k = 1..6, c[k]*y'^k)"), "sum(k = 1..6, (c[k] * (y' ^ k)))");
  const ParseResult result = parse_text("z = sum(j = 0 .. 12, a[j])");
  const auto& sum = boost::get<x3::forward_ast<ast::SumOver>>(testing::statement_as<ast::Equation>(result, 0).rhs.first.get()).get();
  EXPECT_EQ(sum.index.name, "j");
  EXPECT_EQ(sum.from, 0);
  EXPECT_EQ(sum.to, 12);
  EXPECT_EQ(ast_text::text(sum.body), "a[j]");
}

TEST(ParseExpression, ContinuesAfterOperatorsOpeningBracketsCommasAndEquals) {
  EXPECT_EQ(statement_text("z = a +\n b"), "z = (a + b)");
  EXPECT_EQ(statement_text("z = a *\n b -\n c /\n d ^\n 2"), "z = ((a * b) - (c / (d ^ 2)))");
  EXPECT_EQ(statement_text("z = f(\n a,\n b)"), "z = f(a, b)");
  EXPECT_EQ(statement_text("z = c[\n k]"), "z = c[k]");
  EXPECT_EQ(statement_text("z =\n a"), "z = a");
  EXPECT_EQ(statement_text("z = [y <=\n 0 and\n y > 1]"), "z = [y <= 0 and y > 1]");
  EXPECT_EQ(statement_text("z = -\n y"), "z = -y");
}

TEST(ParseExpression, ContinuationLinesMayBeBlankOrComments) {
  EXPECT_EQ(statement_text("z = a +  # first\n\n   # between\n\n b"), "z = (a + b)");
}

TEST(ParseExpression, ClosingBracketMayStartALine) {
  EXPECT_EQ(statement_text("z = f(\n  a,\n  b\n)"), "z = f(a, b)");
  EXPECT_EQ(statement_text("z = c[\n  k\n  # why not\n]"), "z = c[k]");
}

TEST(ParseExpression, NewlineElsewhereEndsTheStatement) {
  EXPECT_EQ(testing::parsed_text("z = a\n+ b = c"), "z = a\n+b = c\n");
}

TEST(ParseExpression, CrLfLineEndings) {
  EXPECT_EQ(testing::parsed_text("z = a +\r\n b\r\nw = 1\r\n"), "z = (a + b)\nw = 1\n");
}

}  // namespace
}  // namespace sidc
