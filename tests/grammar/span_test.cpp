// Every annotated node knows where it was written: ParseResult::span gives its byte range, and
// SourceFile turns that into line and column.
#include <gtest/gtest.h>

#include "tests/grammar/parse_text.hpp"

namespace sidc {
namespace {

namespace x3 = boost::spirit::x3;
using testing::parse_text;
using testing::statement_as;

// The text a span covers.
std::string covered(const ParseResult& result, const Span& span) {
  EXPECT_TRUE(span.known());
  return result.source->text.substr(span.begin, span.end - span.begin);
}

TEST(Span, NodesOfAnEquationOnTheThirdLine) {
  const ParseResult result = parse_text("model m\n# the equation\na1*y'' + a2*y = x  # eq. 1-1.2\n");
  ASSERT_EQ(result.model.statements.size(), 2u) << result.diagnostics.render_all();
  const auto& equation = statement_as<ast::Equation>(result, 1);
  EXPECT_EQ(covered(result, result.span(equation)), "a1*y'' + a2*y = x");
  EXPECT_EQ(result.span(equation).start().line, 3);
  EXPECT_EQ(result.span(equation).start().column, 1);

  const auto& sum = equation.lhs;
  EXPECT_EQ(covered(result, result.span(sum)), "a1*y'' + a2*y");
  const auto& product = boost::get<x3::forward_ast<ast::Expression>>(sum.first.get()).get();
  EXPECT_EQ(covered(result, result.span(product)), "a1*y''");
  const auto& derivative = boost::get<ast::Variable>(product.rest[0].operand.get());
  const Span where = result.span(derivative);
  EXPECT_EQ(covered(result, where), "y''");
  EXPECT_EQ(where.start().line, 3);
  EXPECT_EQ(where.start().column, 4);
  EXPECT_EQ(where.length(), 3u);
  EXPECT_EQ(covered(result, result.span(derivative.name)), "y");
  EXPECT_EQ(covered(result, result.span(product.rest[0])), "*y''");
  EXPECT_EQ(covered(result, result.span(sum.rest[0])), "+ a2*y");
  EXPECT_EQ(covered(result, result.span(equation.rhs)), "x");
  const auto& coefficient = boost::get<ast::Variable>(product.first.get());
  EXPECT_EQ(covered(result, result.span(coefficient.name)), "a1");
}

TEST(Span, OperandsOfEveryKind) {
  const ParseResult result = parse_text("z = -2.5e3 + sin(y) + c[k] + [y' <= 0] + sum(k = 1..6, c[k]) + der(y, 1)");
  ASSERT_FALSE(result.diagnostics.has_errors()) << result.diagnostics.render_all();
  const auto& rhs = statement_as<ast::Equation>(result, 0).rhs;
  ASSERT_EQ(rhs.rest.size(), 5u);
  const auto& negative = boost::get<x3::forward_ast<ast::Signed>>(rhs.first.get()).get();
  EXPECT_EQ(covered(result, result.span(negative)), "-2.5e3");
  EXPECT_EQ(covered(result, result.span(boost::get<ast::Number>(negative.operand.get()))), "2.5e3");
  const auto& call = boost::get<x3::forward_ast<ast::Call>>(rhs.rest[0].operand.get()).get();
  EXPECT_EQ(covered(result, result.span(call)), "sin(y)");
  EXPECT_EQ(covered(result, result.span(call.callee)), "sin");
  EXPECT_EQ(covered(result, result.span(call.arguments[0])), "y");
  const auto& member = boost::get<x3::forward_ast<ast::Indexed>>(rhs.rest[1].operand.get()).get();
  EXPECT_EQ(covered(result, result.span(member)), "c[k]");
  EXPECT_EQ(covered(result, result.span(member.index)), "k");
  const auto& guard = boost::get<x3::forward_ast<ast::Guard>>(rhs.rest[2].operand.get()).get();
  EXPECT_EQ(covered(result, result.span(guard)), "[y' <= 0]");
  EXPECT_EQ(covered(result, result.span(guard.conditions[0])), "y' <= 0");
  const auto& sum = boost::get<x3::forward_ast<ast::SumOver>>(rhs.rest[3].operand.get()).get();
  EXPECT_EQ(covered(result, result.span(sum)), "sum(k = 1..6, c[k])");
  EXPECT_EQ(covered(result, result.span(sum.index)), "k");
  EXPECT_EQ(covered(result, result.span(sum.body)), "c[k]");
  const auto& builtin = boost::get<x3::forward_ast<ast::Call>>(rhs.rest[4].operand.get()).get();
  EXPECT_EQ(covered(result, result.span(builtin)), "der(y, 1)");
  EXPECT_EQ(covered(result, result.span(builtin.callee)), "der");
  EXPECT_EQ(covered(result, result.span(builtin.callee.name)), "der");
}

TEST(Span, StatementsAndTheirItems) {
  const std::string text =
      "model m\n"
      "input x = sin(t), w\n"
      "param a1, c[1..6]\n"
      "const g = 9.81\n"
      "data \"r.csv\" (y = \"disp\")\n"
      "set integrate = 1\n";
  const ParseResult result = parse_text(text);
  ASSERT_EQ(result.model.statements.size(), 6u) << result.diagnostics.render_all();
  EXPECT_EQ(covered(result, result.span(statement_as<ast::ModelName>(result, 0))), "model m");
  EXPECT_EQ(covered(result, result.span(statement_as<ast::ModelName>(result, 0).name)), "m");
  const auto& inputs = statement_as<ast::SignalDeclaration>(result, 1);
  EXPECT_EQ(covered(result, result.span(inputs)), "input x = sin(t), w");
  EXPECT_EQ(covered(result, result.span(inputs.signals[0])), "x = sin(t)");
  EXPECT_EQ(covered(result, result.span(*inputs.signals[0].definition)), "sin(t)");
  EXPECT_EQ(covered(result, result.span(inputs.signals[1])), "w");
  const auto& parameters = statement_as<ast::ParameterDeclaration>(result, 2);
  EXPECT_EQ(covered(result, result.span(parameters)), "param a1, c[1..6]");
  EXPECT_EQ(covered(result, result.span(parameters.parameters[1])), "c[1..6]");
  EXPECT_EQ(covered(result, result.span(parameters.parameters[1].name)), "c");
  const auto& constants = statement_as<ast::ConstantDeclaration>(result, 3);
  EXPECT_EQ(covered(result, result.span(constants)), "const g = 9.81");
  EXPECT_EQ(covered(result, result.span(constants.constants[0])), "g = 9.81");
  const auto& data = statement_as<ast::DataStatement>(result, 4);
  EXPECT_EQ(covered(result, result.span(data)), "data \"r.csv\" (y = \"disp\")");
  EXPECT_EQ(covered(result, result.span(data.bindings[0])), "y = \"disp\"");
  const auto& setting = statement_as<ast::Setting>(result, 5);
  EXPECT_EQ(covered(result, result.span(setting)), "set integrate = 1");
  EXPECT_EQ(covered(result, result.span(setting.key)), "integrate");
  EXPECT_EQ(result.span(setting).start().line, 6);
}

TEST(Span, NodeOnAContinuationLine) {
  const ParseResult result = parse_text("z = a +\n    b'\n");
  const auto& rhs = statement_as<ast::Equation>(result, 0).rhs;
  const Span where = result.span(boost::get<ast::Variable>(rhs.rest[0].operand.get()));
  EXPECT_EQ(where.start().line, 2);
  EXPECT_EQ(where.start().column, 5);
  EXPECT_EQ(covered(result, result.span(statement_as<ast::Equation>(result, 0))), "z = a +\n    b'");
}

TEST(Span, CrLfLinesCountLikeLfLines) {
  const ParseResult result = parse_text("model m\r\n\r\nz = y'\r\n");
  const auto& equation = statement_as<ast::Equation>(result, 1);
  EXPECT_EQ(result.span(equation).start().line, 3);
  EXPECT_EQ(covered(result, result.span(equation)), "z = y'");
}

TEST(Span, StatementsAfterAFailedOneStillHaveTheirSpans) {
  const ParseResult result = parse_text("z = (a\nw = b*c\n");
  ASSERT_EQ(result.model.statements.size(), 1u);
  const auto& equation = statement_as<ast::Equation>(result, 0);
  EXPECT_EQ(covered(result, result.span(equation)), "w = b*c");
  EXPECT_EQ(covered(result, result.span(equation.rhs)), "b*c");
  // The failed statement left no entries: every entry belongs to the statement that parsed.
  for (const auto& [begin, end] : result.positions) EXPECT_GE(begin, result.source->text.find("w ="));
}

TEST(Span, NodeThatWasNeverParsedHasAnUnknownSpan) {
  const ParseResult result = parse_text("z = y");
  EXPECT_FALSE(result.span(ast::Variable{}).known());
}

}  // namespace
}  // namespace sidc
