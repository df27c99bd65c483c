// Syntax errors: what the message says, where it points, and that one run reports several.
#include <gtest/gtest.h>

#include "diagnostics/model_catalogue.hpp"
#include "tests/grammar/parse_text.hpp"

namespace sidc {
namespace {

using testing::diagnostic_codes;
using testing::parse_text;

// The first line of the only diagnostic of `text` (`file:line:col: error: message`).
std::string only_error(const std::string& text) {
  const ParseResult result = parse_text(text);
  if (result.diagnostics.items.size() != 1) return "diagnostics: " + result.diagnostics.render_all();
  const std::string rendered = render(result.diagnostics.items[0]);
  return rendered.substr(0, rendered.find('\n'));
}

const Diagnostic& first_diagnostic(const ParseResult& result) {
  static const Diagnostic none;
  return result.diagnostics.items.empty() ? none : result.diagnostics.items[0];
}

TEST(SyntaxError, MissingOperandAfterAnOperator) {
  EXPECT_EQ(only_error("model m\ninput x\na1*y' + * y = x\n"),
            "model.sid:3:9: error: expected an operand such as `a1*y'` or `(y - 1)`, found `*`");
}

TEST(SyntaxError, MissingFactorAfterMultiplication) {
  EXPECT_EQ(only_error("z = a*/b"), "model.sid:1:7: error: expected a factor such as `y'`, `2.5` or `(y - 1)`, found `/`");
}

TEST(SyntaxError, MissingRightSide) {
  EXPECT_EQ(only_error("z = "), "model.sid:1:5: error: expected an expression such as `a1*y'' + a2*y`, found the end of the file");
  EXPECT_EQ(only_error("z =  # nothing\nw = 1"),
            "model.sid:2:3: error: expected the end of the statement, found `=`");
}

TEST(SyntaxError, MissingClosingParenthesisAtTheEndOfTheLine) {
  EXPECT_EQ(only_error("z = sin(x\n"), "model.sid:1:10: error: expected a closing `)`, found the end of the line");
  EXPECT_EQ(only_error("z = (x; w = 1)"), "model.sid:1:7: error: expected a closing `)`, found `;`");
}

TEST(SyntaxError, MissingClosingBracket) {
  EXPECT_EQ(only_error("z = c[k"), "model.sid:1:8: error: expected a closing `]`, found the end of the file");
}

TEST(SyntaxError, EquationWithoutEquals) {
  EXPECT_EQ(only_error("a1*y'' x"), "model.sid:1:8: error: expected `=` between the two sides of an equation, found `x`");
}

TEST(SyntaxError, TwoOperandsWithoutAnOperator) {
  EXPECT_EQ(only_error("z = 2y"), "model.sid:1:6: error: expected the end of the statement, found `y`");
}

TEST(SyntaxError, StatementStartingWithAnOperator) {
  EXPECT_EQ(only_error("* y = x"),
            "model.sid:1:1: error: expected a statement such as `param a1` or `a1*y' + y = x`, found `*`");
}

TEST(SyntaxError, ReservedWordAsAName) {
  const ParseResult result = parse_text("param a1, model");
  EXPECT_EQ(diagnostic_codes(result), "reserved-word");
  EXPECT_EQ(first_diagnostic(result).message, "expected a parameter name, found the reserved word `model`");
  EXPECT_EQ(first_diagnostic(result).span.start().column, 11);
  EXPECT_EQ(first_diagnostic(result).span.length(), 5u);
  EXPECT_EQ(diagnostic_codes(parse_text("input sum")), "reserved-word");
  EXPECT_EQ(diagnostic_codes(parse_text("z = data + 1")), "reserved-word");
  EXPECT_EQ(diagnostic_codes(parse_text("const int = 3")), "reserved-word");
  EXPECT_EQ(diagnostic_codes(parse_text("set and = 3")), "reserved-word");
}

TEST(SyntaxError, ReservedWordsOnlyAsWholeWords) {
  EXPECT_TRUE(parse_text("param models, input_1, summary, integral\nz = dat*sets").diagnostics.items.empty());
}

TEST(SyntaxError, MisspelledStatementKeyword) {
  const ParseResult result = parse_text("parm a1, a2");
  EXPECT_EQ(diagnostic_codes(result), "unknown-statement");
  EXPECT_EQ(first_diagnostic(result).message, "`parm` is not a statement keyword");
  EXPECT_EQ(first_diagnostic(result).hint, "did you mean `param`?");
  EXPECT_EQ(first_diagnostic(result).span.length(), 4u);
  EXPECT_EQ(first_diagnostic(parse_text("ouput y")).hint, "did you mean `output`?");
  // Not every lone word is a misspelled keyword.
  EXPECT_EQ(diagnostic_codes(parse_text("velocity y")), "syntax");
}

TEST(SyntaxError, UnterminatedString) {
  const ParseResult result = parse_text("data \"record.csv\ny = x");
  EXPECT_EQ(diagnostic_codes(result), "unterminated-string");
  EXPECT_EQ(first_diagnostic(result).span.start().column, 6);
  EXPECT_EQ(first_diagnostic(result).span.length(), 11u);
  EXPECT_EQ(result.model.statements.size(), 1u) << "the next line is read as usual";
  EXPECT_EQ(diagnostic_codes(parse_text("data \"x.csv\" (y = \"disp)")), "unterminated-string");
}

TEST(SyntaxError, DataNeedsAQuotedPath) {
  EXPECT_EQ(only_error("data record.csv"),
            "model.sid:1:6: error: expected a quoted file name such as `\"record.csv\"`, found `record`");
}

TEST(SyntaxError, SettingWithoutValue) {
  EXPECT_EQ(only_error("set integrate =   # later\n"),
            "model.sid:1:26: error: expected a value, as in `set integrate = 1`, found the end of the line");
  EXPECT_EQ(only_error("set integrate 1"), "model.sid:1:15: error: expected `=` between the setting and its value, found `1`");
}

TEST(SyntaxError, GuardWithoutComparison) {
  EXPECT_EQ(only_error("z = [y]"),
            "model.sid:1:7: error: expected a comparison operator `<`, `<=`, `>` or `>=`, found `]`");
  EXPECT_EQ(only_error("z = [y > 0 and]"), "model.sid:1:15: error: expected a comparison such as `y' <= 0`, found `]`");
}

TEST(SyntaxError, SumErrors) {
  EXPECT_EQ(only_error("z = sum(k = 1.5..6, y)"),
            "model.sid:1:14: error: expected `..` between the bounds of a range, found `.5`");
  EXPECT_EQ(only_error("z = sum(k = 1..6 y)"), "model.sid:1:18: error: expected `,` before the summand, found `y`");
  EXPECT_EQ(only_error("z = sum + 1"), "model.sid:1:9: error: expected `(` after `sum`, found `+`");
}

TEST(SyntaxError, FamilyRangeNeedsIntegers) {
  EXPECT_EQ(only_error("param c[1..n]"), "model.sid:1:12: error: expected an integer, found `n`");
}

TEST(SyntaxError, CharactersOutsideTheLanguage) {
  const ParseResult dollar = parse_text("z = x $ 2");
  EXPECT_EQ(diagnostic_codes(dollar), "unexpected-character");
  EXPECT_EQ(first_diagnostic(dollar).message, "unexpected character `$`");
  EXPECT_EQ(first_diagnostic(dollar).span.start().column, 7);
  const ParseResult accented = parse_text("z = caf\xc3\xa9");
  EXPECT_EQ(diagnostic_codes(accented), "unexpected-character");
  EXPECT_EQ(first_diagnostic(accented).message, "unexpected character `\xc3\xa9`");
  EXPECT_EQ(first_diagnostic(accented).span.length(), 2u);
}

TEST(SyntaxError, UnicodeIsFineInCommentsAndStrings) {
  const ParseResult result = parse_text("# Bernhart, 1964 \xe2\x80\x94 caf\xc3\xa9\ndata \"m\xc3\xa9sures.csv\"");
  EXPECT_TRUE(result.diagnostics.items.empty()) << result.diagnostics.render_all();
}

TEST(SyntaxError, EveryErrorHasAHint) {
  for (const std::string text : {"z = a*/b", "z = sin(x", "a1 y", "z = 2y", "param model", "parm a", "data x",
                                 "data \"x", "set a =", "z = [y]", "z = sum(k = 1, y)", "input 3", "output y,",
                                 "const g", "model 1", "z = der y", "data \"x\" (y)", "z = x $"}) {
    const ParseResult result = parse_text(text);
    ASSERT_EQ(result.diagnostics.items.size(), 1u) << text;
    EXPECT_FALSE(result.diagnostics.items[0].hint.empty()) << text << "\n" << result.diagnostics.render_all();
    EXPECT_TRUE(result.diagnostics.items[0].span.known()) << text;
  }
}

TEST(SyntaxError, SeveralErrorsInOneRun) {
  const ParseResult result = parse_text(
      "model m\n"
      "input x\n"
      "param a1, a2,\n"      // 3: trailing comma continues onto the next line...
      "output y\n"           // 4: ...which is then no parameter name
      "a1*y'' + * y = x\n"   // 5
      "a2*y = x\n"           // 6: fine
      "z = sin(x\n"          // 7
      "w = (1 + 2)\n");      // 8: fine
  ASSERT_EQ(result.diagnostics.items.size(), 3u) << result.diagnostics.render_all();
  EXPECT_EQ(result.diagnostics.items[0].span.start().line, 4);
  EXPECT_EQ(result.diagnostics.items[0].code, "reserved-word");
  EXPECT_EQ(result.diagnostics.items[1].span.start().line, 5);
  EXPECT_EQ(result.diagnostics.items[2].span.start().line, 7);
  EXPECT_EQ(result.model.statements.size(), 4u);
  EXPECT_EQ(ast_text::text(result.model.statements[3]), "w = (1 + 2)");
}

TEST(SyntaxError, StopsAfterTwentyErrorsWithANote) {
  std::string text;
  for (int i = 0; i < 30; ++i) text += "z = * " + std::to_string(i) + "\n";
  const ParseResult result = parse_text(text);
  ASSERT_EQ(result.diagnostics.items.size(), 21u);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(result.diagnostics.items[static_cast<std::size_t>(i)].severity, Severity::error);
  const Diagnostic& note = result.diagnostics.items.back();
  EXPECT_EQ(note.severity, Severity::note);
  EXPECT_EQ(note.code, "too-many-errors");
  EXPECT_EQ(note.span.start().line, 21);
}

}  // namespace
}  // namespace sidc
