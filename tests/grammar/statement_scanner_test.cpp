// The line rules, as the scanner applies them before X3 sees a statement: where statements end,
// how nesting is measured, and which bytes are invalid.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "grammar/statement_scanner.hpp"

namespace sidc {
namespace {

using parser::next_statement;

// The statements of `text` as the scanner cuts them.
std::vector<std::string> statements(const std::string& text) {
  std::vector<std::string> out;
  std::size_t from = 0;
  while (const auto extent = next_statement(text, from)) {
    out.push_back(text.substr(extent->begin, extent->end - extent->begin));
    from = extent->next;
  }
  return out;
}

using Lines = std::vector<std::string>;

TEST(StatementScanner, NewlineOrSemicolonEndsAStatement) {
  EXPECT_EQ(statements("a = 1\nb = 2;c = 3"), (Lines{"a = 1", "b = 2", "c = 3"}));
  EXPECT_EQ(statements("\n\n  a = 1  \n\n"), (Lines{"a = 1  "}));
}

TEST(StatementScanner, ContinuationTokens) {
  for (const std::string token : {"+", "-", "*", "/", "^", "(", "[", ",", "=", "<", "<=", ">", ">=", "and", "against"})
    EXPECT_EQ(statements("a " + token + "\n b\nc").size(), 2u) << token;
  EXPECT_EQ(statements("a ..\n b").size(), 2u);
  EXPECT_EQ(statements("a'\n b").size(), 2u);
  EXPECT_EQ(statements("a)\n b").size(), 2u);
  // Whole words only: a name that merely starts with one is an operand.
  EXPECT_EQ(statements("a + andy\n b").size(), 2u);
  EXPECT_EQ(statements("a + againstx\n b").size(), 2u);
}

TEST(StatementScanner, CommentsAndBlankLinesDoNotBreakAContinuation) {
  EXPECT_EQ(statements("a = b +  # more\n\n# still\n c\nd"), (Lines{"a = b +  # more\n\n# still\n c", "d"}));
}

TEST(StatementScanner, ClosingBracketAfterANewline) {
  EXPECT_EQ(statements("f(a,\n b\n)\nc"), (Lines{"f(a,\n b\n)", "c"}));
  EXPECT_EQ(statements("f(a\n b)"), (Lines{"f(a", "b)"}));
  EXPECT_EQ(statements(")\n)"), (Lines{")", ")"})) << "only inside brackets";
}

TEST(StatementScanner, SemicolonInsideBracketsDoesNotEndTheStatement) {
  EXPECT_EQ(statements("f(a; b); c"), (Lines{"f(a; b)", "c"}));
}

TEST(StatementScanner, StringsAndCommentsHideTheirCharacters) {
  EXPECT_EQ(statements("data \"a;b#(\" # ; (\nc"), (Lines{"data \"a;b#(\" # ; (", "c"}));
  EXPECT_EQ(statements("data \"open\nc"), (Lines{"data \"open", "c"})) << "a string ends with its line";
}

TEST(StatementScanner, SettingsEndAtTheirLine) {
  EXPECT_EQ(statements("set a = (1 +\nb"), (Lines{"set a = (1 +", "b"}));
  EXPECT_EQ(statements("set a = \"x;y\"; b"), (Lines{"set a = \"x", "y\"; b"})) << "quotes mean nothing to `set`";
  EXPECT_EQ(statements("set a = 1 # c; d\ne"), (Lines{"set a = 1 # c; d", "e"}));
  EXPECT_EQ(statements("settle = 1 +\n 2"), (Lines{"settle = 1 +\n 2"})) << "`set` is a whole word";
}

TEST(StatementScanner, CrLf) {
  EXPECT_EQ(statements("a = b +\r\n c\r\nd\r\n"), (Lines{"a = b +\r\n c\r", "d\r"}));
}

// The nesting of the whole text as one statement: the offset where it first exceeds `limit`
// levels, computed by building the text to just past the limit.
bool too_deep(const std::string& text) { return next_statement(text, 0)->too_deep_at.has_value(); }

std::string times(const std::string& piece, int n) {
  std::string out;
  for (int i = 0; i < n; ++i) out += piece;
  return out;
}

TEST(StatementScanner, NestingCountsBracketsSignsAndPowers) {
  const int limit = parser::nesting_limit;
  EXPECT_FALSE(too_deep(times("(", limit)));
  EXPECT_TRUE(too_deep(times("(", limit + 1)));
  EXPECT_TRUE(too_deep(times("[", limit + 1)));
  EXPECT_TRUE(too_deep("z = " + times("-", limit + 1) + "y"));
  EXPECT_TRUE(too_deep("z = y" + times("^y", limit + 1)));
  EXPECT_TRUE(too_deep(times("-(", limit / 2 + 1)));
}

TEST(StatementScanner, NestingEndsWithItsBracketOrChain) {
  const int limit = parser::nesting_limit;
  EXPECT_FALSE(too_deep(times("(y) + ", 3 * limit)));
  EXPECT_FALSE(too_deep(times("-y + ", 3 * limit)));
  EXPECT_FALSE(too_deep(times("y^2*", 3 * limit)));
  EXPECT_FALSE(too_deep(times("-a*", 3 * limit)));
  EXPECT_FALSE(too_deep(times("f(-x, -y) - ", 3 * limit)));
  EXPECT_FALSE(too_deep(times("[y > -1 and y < -2]*", 3 * limit)));
  // ...but an exponent's sign is part of its number, not a break in the chain.
  EXPECT_TRUE(too_deep("z = y" + times("^2e-1", limit + 1)));
}

TEST(StatementScanner, InvalidBytes) {
  EXPECT_EQ(next_statement(std::string("ab\0c", 4), 0)->invalid_byte, 2u);
  EXPECT_EQ(next_statement("a = \"\xc3\xa9\" # \xe2\x80\x94", 0)->invalid_byte, std::nullopt);
  EXPECT_EQ(next_statement("a = \"\xc3\" b", 0)->invalid_byte, 5u);
  EXPECT_EQ(next_statement("a\rb", 0)->invalid_byte, 1u);
  const auto comment = next_statement("\n# bad \x01 here\nz = 1", 0);
  ASSERT_TRUE(comment.has_value());
  EXPECT_TRUE(comment->comment_only);
  EXPECT_EQ(comment->invalid_byte, 7u);
}

TEST(StatementScanner, ValidCharacterLengths) {
  using parser::valid_character_length;
  EXPECT_EQ(valid_character_length("a", 0), 1u);
  EXPECT_EQ(valid_character_length("\t", 0), 1u);
  EXPECT_EQ(valid_character_length("\r\n", 0), 1u);
  EXPECT_EQ(valid_character_length("\r", 0), 0u);
  EXPECT_EQ(valid_character_length("\x7f", 0), 0u);
  EXPECT_EQ(valid_character_length("\xc3\xa9", 0), 2u);
  EXPECT_EQ(valid_character_length("\xe2\x80\x94", 0), 3u);
  EXPECT_EQ(valid_character_length("\xf0\x9f\x98\x80", 0), 4u);
  EXPECT_EQ(valid_character_length("\xc0\x80", 0), 0u) << "overlong";
  EXPECT_EQ(valid_character_length("\xed\xa0\x80", 0), 0u) << "surrogate";
  EXPECT_EQ(valid_character_length("\xf4\x90\x80\x80", 0), 0u) << "above U+10FFFF";
  EXPECT_EQ(valid_character_length("\xe2\x80", 0), 0u) << "truncated";
}

}  // namespace
}  // namespace sidc
