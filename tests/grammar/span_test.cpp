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

// Visits every node of a model and checks its span: known, not empty, and covering exactly the
// text of names, numbers and variables.
struct SpanChecker {
  const ParseResult& result;
  int nodes = 0;

  void check(const x3::position_tagged& node, const char* kind) {
    ++nodes;
    const Span where = result.span(node);
    ASSERT_TRUE(where.known()) << kind;
    EXPECT_LT(where.begin, where.end) << kind;
  }
  void operator()(const ast::Identifier& n) {
    check(n, "Identifier");
    EXPECT_EQ(covered(result, result.span(n)), n.name);
  }
  void operator()(const ast::Number& n) {
    check(n, "Number");
    EXPECT_EQ(covered(result, result.span(n)), n.text);
  }
  void operator()(const ast::Variable& n) {
    check(n, "Variable");
    EXPECT_EQ(covered(result, result.span(n)), n.name.name + n.primes);
    (*this)(n.name);
  }
  void operator()(const ast::Signed& n) {
    check(n, "Signed");
    (*this)(n.operand);
  }
  void operator()(const ast::Call& n) {
    check(n, "Call");
    (*this)(n.callee);
    for (const auto& a : n.arguments) (*this)(a);
  }
  void operator()(const ast::Indexed& n) {
    check(n, "Indexed");
    (*this)(n.name);
    (*this)(n.index);
  }
  void operator()(const ast::Guard& n) {
    check(n, "Guard");
    for (const auto& c : n.conditions) {
      check(c, "Comparison");
      (*this)(c.lhs);
      (*this)(c.rhs);
    }
  }
  void operator()(const ast::SumOver& n) {
    check(n, "SumOver");
    (*this)(n.index);
    (*this)(n.body);
  }
  void operator()(const ast::Expression& n) {
    check(n, "Expression");
    (*this)(n.first);
    for (const auto& o : n.rest) {
      check(o, "Operation");
      (*this)(o.operand);
    }
  }
  void operator()(const ast::Operand& n) { boost::apply_visitor(*this, n.get()); }
  template <typename T>
  void operator()(const x3::forward_ast<T>& n) { (*this)(n.get()); }

  void operator()(const ast::ModelName& n) {
    check(n, "ModelName");
    (*this)(n.name);
  }
  void operator()(const ast::SignalDeclaration& n) {
    check(n, "SignalDeclaration");
    for (const auto& item : n.signals) {
      check(item, "SignalItem");
      (*this)(item.name);
      if (item.definition) (*this)(*item.definition);
    }
  }
  void operator()(const ast::ParameterDeclaration& n) {
    check(n, "ParameterDeclaration");
    for (const auto& item : n.parameters) {
      check(item, "ParameterItem");
      (*this)(item.name);
    }
  }
  void operator()(const ast::ConstantDeclaration& n) {
    check(n, "ConstantDeclaration");
    for (const auto& item : n.constants) {
      check(item, "ConstantItem");
      (*this)(item.name);
      (*this)(item.value);
    }
  }
  void operator()(const ast::DataStatement& n) {
    check(n, "DataStatement");
    for (const auto& binding : n.bindings) {
      check(binding, "ColumnBinding");
      (*this)(binding.signal);
    }
  }
  void operator()(const ast::Setting& n) {
    check(n, "Setting");
    (*this)(n.key);
    EXPECT_EQ(result.source->text.substr(n.value_offset, n.value.size()), n.value);
  }
  void operator()(const ast::WeightsSetting& n) {
    check(n, "WeightsSetting");
    if (const auto* e = boost::get<ast::Expression>(&n.value.get())) (*this)(*e);
  }
  void operator()(const ast::PlotStatement& n) {
    check(n, "PlotStatement");
    (*this)(n.name);
    (*this)(n.argument);
    (*this)(n.fitted);
    if (n.truth) (*this)(*n.truth);
  }
  void operator()(const ast::Equation& n) {
    check(n, "Equation");
    (*this)(n.lhs);
    (*this)(n.rhs);
  }
};

TEST(Span, EveryNodeOfEveryKindHasOne) {
  const ParseResult result = parse_text(
      "model quasi_linear\n"
      "input x = 60*sin(4*pi*t), w\noutput y\n"
      "param m, a[1..24]\nconst g = 9.81, L = -2*g\n"
      "data \"r.csv\" (t = \"time\", y = disp, y' = v)\nset integrate = 1 # once\n"
      "set weights = 1/(1 + y'^2)\n"
      "m*y'' + sum(k = 1..6, a[k]*y'^k)*[y' <= 0 and y > -2] +\n"
      "  der(y^3, 1) + int(y) + y'(0) - (y/g)^-1 = x\n"
      "plot damper(y') = a[1]*y' against 2*y'\n");
  ASSERT_EQ(result.model.statements.size(), 10u) << result.diagnostics.render_all();
  SpanChecker checker{result};
  for (const auto& statement : result.model.statements) boost::apply_visitor(checker, statement.get());
  EXPECT_GT(checker.nodes, 80);
}

TEST(Span, NodeThatWasNeverParsedHasAnUnknownSpan) {
  const ParseResult result = parse_text("z = y");
  EXPECT_FALSE(result.span(ast::Variable{}).known());
}

}  // namespace
}  // namespace sidc
