// The AST of every statement, and of every equation of the thesis written in the language.
#include <gtest/gtest.h>

#include "tests/grammar/parse_text.hpp"

namespace sidc {
namespace {

using testing::parse_text;
using testing::parsed_text;
using testing::statement_as;
using testing::statement_text;

TEST(ParseStatement, ModelName) {
  const ParseResult result = parse_text("model quasi_linear");
  ASSERT_EQ(result.model.statements.size(), 1u) << result.diagnostics.render_all();
  EXPECT_EQ(statement_as<ast::ModelName>(result, 0).name.name, "quasi_linear");
}

TEST(ParseStatement, InputsAndOutputs) {
  const ParseResult result = parse_text("input x1, x2\noutput y");
  ASSERT_EQ(result.model.statements.size(), 2u) << result.diagnostics.render_all();
  const auto& inputs = statement_as<ast::SignalDeclaration>(result, 0);
  EXPECT_EQ(inputs.kind, "input");
  ASSERT_EQ(inputs.signals.size(), 2u);
  EXPECT_EQ(inputs.signals[0].name.name, "x1");
  EXPECT_EQ(inputs.signals[1].name.name, "x2");
  EXPECT_FALSE(inputs.signals[0].definition.has_value());
  const auto& outputs = statement_as<ast::SignalDeclaration>(result, 1);
  EXPECT_EQ(outputs.kind, "output");
  ASSERT_EQ(outputs.signals.size(), 1u);
  EXPECT_EQ(outputs.signals[0].name.name, "y");
}

TEST(ParseStatement, InputGivenAsAnExpressionOfTime) {
  const ParseResult result = parse_text("input x = 60*sin(4*pi*t), w");
  const auto& inputs = statement_as<ast::SignalDeclaration>(result, 0);
  ASSERT_EQ(inputs.signals.size(), 2u);
  ASSERT_TRUE(inputs.signals[0].definition.has_value());
  EXPECT_EQ(ast_text::text(*inputs.signals[0].definition), "(60 * sin((4 * pi * t)))");
  EXPECT_FALSE(inputs.signals[1].definition.has_value());
}

TEST(ParseStatement, ParametersAndFamilies) {
  const ParseResult result = parse_text("param a1, c[1..6], a2, d[0 .. 12], e[-2..2]");
  const auto& declaration = statement_as<ast::ParameterDeclaration>(result, 0);
  ASSERT_EQ(declaration.parameters.size(), 5u) << result.diagnostics.render_all();
  EXPECT_EQ(declaration.parameters[0].name.name, "a1");
  EXPECT_FALSE(declaration.parameters[0].from.has_value());
  EXPECT_FALSE(declaration.parameters[0].to.has_value());
  EXPECT_EQ(declaration.parameters[1].name.name, "c");
  EXPECT_EQ(declaration.parameters[1].from, 1);
  EXPECT_EQ(declaration.parameters[1].to, 6);
  EXPECT_FALSE(declaration.parameters[2].from.has_value());
  EXPECT_EQ(declaration.parameters[3].from, 0);
  EXPECT_EQ(declaration.parameters[3].to, 12);
  EXPECT_EQ(declaration.parameters[4].from, -2);
  EXPECT_EQ(declaration.parameters[4].to, 2);
}

TEST(ParseStatement, Constants) {
  const ParseResult result = parse_text("const g = 9.81, L = 2*g");
  const auto& declaration = statement_as<ast::ConstantDeclaration>(result, 0);
  ASSERT_EQ(declaration.constants.size(), 2u) << result.diagnostics.render_all();
  EXPECT_EQ(declaration.constants[0].name.name, "g");
  EXPECT_EQ(ast_text::text(declaration.constants[0].value), "9.81");
  EXPECT_EQ(declaration.constants[1].name.name, "L");
  EXPECT_EQ(ast_text::text(declaration.constants[1].value), "(2 * g)");
}

TEST(ParseStatement, DataWithoutBindings) {
  const ParseResult result = parse_text("data \"appendix_a.csv\"");
  const auto& data = statement_as<ast::DataStatement>(result, 0);
  EXPECT_EQ(data.path, "appendix_a.csv");
  EXPECT_TRUE(data.bindings.empty());
}

TEST(ParseStatement, DataWithQuotedAndPlainColumns) {
  const ParseResult result = parse_text("data \"runs/rec 1.csv\" (t = \"time (s)\", y = displacement, x = data)");
  const auto& data = statement_as<ast::DataStatement>(result, 0);
  EXPECT_EQ(data.path, "runs/rec 1.csv");
  ASSERT_EQ(data.bindings.size(), 3u) << result.diagnostics.render_all();
  EXPECT_EQ(data.bindings[0].signal.name.name, "t");
  EXPECT_EQ(data.bindings[0].column, "time (s)");
  EXPECT_EQ(data.bindings[1].signal.name.name, "y");
  EXPECT_EQ(data.bindings[1].column, "displacement");
  // A plain column name may be a reserved word: it names a CSV column, not a model quantity.
  EXPECT_EQ(data.bindings[2].column, "data");
}

TEST(ParseStatement, DataBindingsOverSeveralLines) {
  EXPECT_EQ(statement_text("data \"r.csv\" (\n  t = \"time\",\n  y = \"y\"\n)"), "data <r.csv> (t = <time>, y = <y>)");
}

TEST(ParseStatement, DataBindsAnExactDerivative) {
  EXPECT_EQ(statement_text("data \"a.csv\" (y = \"y\", y' = \"ydot\", y'' = yddot)"),
            "data <a.csv> (y = <y>, y' = <ydot>, y'' = <yddot>)");
}

TEST(ParseStatement, WeightsTakeAColumnOrAnExpression) {
  EXPECT_EQ(statement_text("set weights = \"w\"  # a column"), "set weights = column <w>");
  EXPECT_EQ(statement_text("set weights = 1/(1 + y'^2)"), statement_text("set weights = (1/(1 + y'^2))"));
  const ParseResult result = parse_text("set weights = 1/(1 + y'^2)");
  const auto& s = statement_as<ast::WeightsSetting>(result, 0);
  EXPECT_NE(boost::get<ast::Expression>(&s.value.get()), nullptr);
  // Other settings keep their raw text.
  EXPECT_EQ(statement_text("set weightsx = 2"), "set weightsx = <2>@15");
}

TEST(ParseStatement, PlotStatementWithAndWithoutTruth) {
  const ParseResult result = parse_text("plot damper(y') = c1*y' + c2*y'^3 against 0.5*y'");
  const auto& p = statement_as<ast::PlotStatement>(result, 0);
  EXPECT_EQ(p.name.name, "damper");
  EXPECT_EQ(p.argument.name.name, "y");
  EXPECT_EQ(p.argument.primes, "'");
  ASSERT_TRUE(p.truth.has_value());
  EXPECT_EQ(statement_text("plot spring(y) = k1*y"), "plot spring(y) = (k1 * y)");
}

TEST(ParseStatement, PlotIsAReservedWord) {
  const ParseResult result = parse_text("plot*y = x");
  EXPECT_TRUE(result.diagnostics.has_errors());
}

TEST(ParseStatement, SettingValueIsTheTrimmedRawText) {
  const std::string text = "set integrate = 1  # once\nset  title =  two words\t;set x=y";
  const ParseResult result = parse_text(text);
  ASSERT_EQ(result.model.statements.size(), 3u) << result.diagnostics.render_all();
  const auto& first = statement_as<ast::Setting>(result, 0);
  EXPECT_EQ(first.key.name, "integrate");
  EXPECT_EQ(first.value, "1");
  EXPECT_EQ(first.value_offset, text.find("1  #"));
  const auto& second = statement_as<ast::Setting>(result, 1);
  EXPECT_EQ(second.key.name, "title");
  EXPECT_EQ(second.value, "two words");
  EXPECT_EQ(second.value_offset, text.find("two"));
  const auto& third = statement_as<ast::Setting>(result, 2);
  EXPECT_EQ(third.value, "y");
  EXPECT_EQ(third.value_offset, text.size() - 1);
}

TEST(ParseStatement, SettingValueKeepsCharactersOtherStatementsWouldReject) {
  EXPECT_EQ(statement_text("set title = \"fit (2).json\" [x]"), "set title = <\"fit (2).json\" [x]>@12");
  EXPECT_EQ(statement_text("set derivative = savgol(7, 3)"), "set derivative = <savgol(7, 3)>@17");
  EXPECT_EQ(statement_text("set smoothing = 7-point\r\n"), "set smoothing = <7-point>@16");
}

TEST(ParseStatement, SemicolonsSeparateStatements) {
  EXPECT_EQ(parsed_text("input x; output y ;; y = x;"), "input x\noutput y\ny = x\n");
}

TEST(ParseStatement, EmptyTextHasNoStatementsAndNoErrors) {
  for (const std::string text : {"", "\n\n", "   # only a comment\n\n#another", ";;\n;"}) {
    const ParseResult result = parse_text(text);
    EXPECT_TRUE(result.model.statements.empty());
    EXPECT_TRUE(result.diagnostics.items.empty()) << result.diagnostics.render_all();
  }
}

// ---- the thesis, written in the language ------------------------------------------------------

TEST(ThesisEquations, QuasiLinearSystem_1_1_2) {
  EXPECT_EQ(statement_text("a1*y'' + a2*y'*y + a3*x'*y = x"), "((a1 * y'') + (a2 * y' * y) + (a3 * x' * y)) = x");
}

TEST(ThesisEquations, TwoInputsTwoOutputs_2_1_3) {
  EXPECT_EQ(statement_text("a1*y1'' + a2*y1*y2' + a3*x1'*y1^2 + a4 + x2 = 0"),
            "((a1 * y1'') + (a2 * y1 * y2') + (a3 * x1' * (y1 ^ 2)) + a4 + x2) = 0");
}

TEST(ThesisEquations, LinearSystem_2_2_2) {
  EXPECT_EQ(statement_text("a1*y'' + a2*y' + a3*y = x"), "((a1 * y'') + (a2 * y') + (a3 * y)) = x");
  EXPECT_EQ(statement_text("a1*y''' + a2*y'' + a3*y' + a4*y = x"),
            "((a1 * y''') + (a2 * y'') + (a3 * y') + (a4 * y)) = x");
}

TEST(ThesisEquations, VanDerPol_2_2_6) {
  EXPECT_EQ(statement_text("y'' + a1*y' + a2*y'*y^2 + a3*y = 0"),
            "(y'' + (a1 * y') + (a2 * y' * (y ^ 2)) + (a3 * y)) = 0");
}

TEST(ThesisEquations, FirstOrderNonlinear_3_2_1) {
  EXPECT_EQ(statement_text("a1*y' + a2*y'*y + a3*y^2 = x"), "((a1 * y') + (a2 * y' * y) + (a3 * (y ^ 2))) = x");
}

TEST(ThesisEquations, PiecewiseSpringAndDamper_4_1_8) {
  const std::string model =
      "model quasi_linear_spring_damper  # section 4-1\n"
      "input x\n"
      "output y\n"
      "param m, a[1..24]\n"
      "# eq. 4-1.7: sixth-order polynomials, one per quadrant of the phase plane (eq. 4-1.9)\n"
      "m*y'' + sum(k = 1..6, a[k]*y'^k)*[y' <= 0] + sum(k = 1..6, a[k + 6]*y'^k)*[y' >= 0] +\n"
      "        sum(k = 1..6, a[k + 12]*y^k)*[y <= 0] + sum(k = 1..6, a[k + 18]*y^k)*[y >= 0] = x\n";
  EXPECT_EQ(parsed_text(model),
            "model quasi_linear_spring_damper\n"
            "input x\n"
            "output y\n"
            "param m, a[1..24]\n"
            "((m * y'') + (sum(k = 1..6, (a[k] * (y' ^ k))) * [y' <= 0]) + (sum(k = 1..6, (a[(k + 6)] * (y' ^ k))) * "
            "[y' >= 0]) + (sum(k = 1..6, (a[(k + 12)] * (y ^ k))) * [y <= 0]) + (sum(k = 1..6, (a[(k + 18)] * (y ^ "
            "k))) * [y >= 0])) = x\n");
}

TEST(ThesisEquations, IntegratedForm_4_1_11) {
  EXPECT_EQ(statement_text("m*y' + int(sum(k = 1..6, a[k]*y'^k)*[y' <= 0]) + a25 = int(x)"),
            "((m * y') + int((sum(k = 1..6, (a[k] * (y' ^ k))) * [y' <= 0])) + a25) = int(x)");
}

TEST(ThesisEquations, ChemicalProcess_4_2_1) {
  EXPECT_EQ(parsed_text("y1' = a1*y1 + a2*y2 + a3*x + a4\n"
                        "y2' = a5*y1 + a6*y2 + a7*x + a8\n"
                        "y1(0) = 0.0; y2(0) = 50.0\n"),
            "y1' = ((a1 * y1) + (a2 * y2) + (a3 * x) + a4)\n"
            "y2' = ((a5 * y1) + (a6 * y2) + (a7 * x) + a8)\n"
            "y1(0) = 0.0\n"
            "y2(0) = 50.0\n");
}

}  // namespace
}  // namespace sidc
