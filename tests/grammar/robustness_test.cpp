// Hostile input: the parser never throws, crashes, hangs or exhausts the stack, and each case
// ends in a diagnostic that says what happened. Big inputs are built here; each case is timed
// (printed) and bounded generously, to catch anything worse than linear.
#include <gtest/gtest.h>

#include <chrono>
#include <iostream>
#include <random>

#include "grammar/statement_scanner.hpp"
#include "tests/grammar/parse_text.hpp"

namespace sidc {
namespace {

using testing::diagnostic_codes;
using testing::parse_text;

// Parses `text`, failing the test if that takes longer than `limit_seconds`. Every case takes
// well under a second even unoptimised; the bound is loose so that a loaded machine does not
// fail it, while anything quadratic in 10 MB would still take hours.
ParseResult timed_parse(const std::string& what, std::string text, double limit_seconds = 10.0) {
  const auto start = std::chrono::steady_clock::now();
  ParseResult result = parse_text(std::move(text));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "[ timing ] " << what << ": " << seconds << " s\n";
  EXPECT_LT(seconds, limit_seconds) << what;
  return result;
}

std::string repeated(const std::string& piece, std::size_t times) {
  std::string out;
  out.reserve(piece.size() * times);
  for (std::size_t i = 0; i < times; ++i) out += piece;
  return out;
}

void expect_spans_inside(const ParseResult& result) {
  for (const auto& d : result.diagnostics.items) {
    ASSERT_TRUE(d.span.known()) << d.message;
    EXPECT_LE(d.span.begin, d.span.end) << d.message;
    EXPECT_LE(d.span.end, result.source->text.size()) << d.message;
  }
  for (const auto& [begin, end] : result.positions) {
    EXPECT_LE(begin, end);
    EXPECT_LE(end, result.source->text.size());
  }
}

TEST(Robustness, NoSourceAtAll) {
  const ParseResult result = parse_model(nullptr);
  EXPECT_TRUE(result.model.statements.empty());
  EXPECT_TRUE(result.diagnostics.items.empty());
}

TEST(Robustness, NulByte) {
  const ParseResult result = parse_text(std::string("z = x\0 + 1\nw = 2", 16));
  EXPECT_EQ(diagnostic_codes(result), "unexpected-character");
  EXPECT_EQ(result.diagnostics.items.at(0).message, "unexpected byte 0x00");
  EXPECT_EQ(result.diagnostics.items.at(0).span.start().column, 6);
  EXPECT_EQ(result.model.statements.size(), 1u) << "the next line is read as usual";
}

TEST(Robustness, InvalidUtf8AnywhereIsReportedAtItsByte) {
  const std::string bad[] = {"\xff", "\xc0\xaf", "\xe2\x82", "\xed\xa0\x80", "\xf5\x80\x80\x80", "\x80"};
  for (const std::string& bytes : bad) {
    for (const std::string& prefix : {std::string("z = "), std::string("# note "), std::string("data \"a")}) {
      const ParseResult result = parse_text(prefix + bytes + "\"\n");
      ASSERT_EQ(diagnostic_codes(result), "unexpected-character") << prefix;
      EXPECT_EQ(result.diagnostics.items[0].span.begin, prefix.size()) << prefix;
      EXPECT_EQ(result.diagnostics.items[0].message.rfind("unexpected byte 0x", 0), 0u);
    }
  }
}

TEST(Robustness, LoneCarriageReturn) {
  const ParseResult result = parse_text("z = x\ry");
  EXPECT_EQ(diagnostic_codes(result), "unexpected-character");
  EXPECT_EQ(result.diagnostics.items.at(0).message, "unexpected byte 0x0d");
}

TEST(Robustness, ByteOrderMarkIsIgnored) {
  const ParseResult result = parse_text("\xEF\xBB\xBFmodel m\nz = y");
  EXPECT_TRUE(result.diagnostics.items.empty()) << result.diagnostics.render_all();
  EXPECT_EQ(result.model.statements.size(), 2u);
}

TEST(Robustness, BinaryGarbage) {
  std::mt19937 random(1964);
  std::string text(256 * 1024, '\0');
  for (char& c : text) c = static_cast<char>(random() & 0xff);
  const ParseResult result = timed_parse("256 KB of random bytes", text);
  ASSERT_FALSE(result.diagnostics.items.empty());
  EXPECT_LE(result.diagnostics.items.size(), 21u);
  expect_spans_inside(result);
}

TEST(Robustness, MillionNestedParentheses) {
  const std::size_t depth = 1'000'000;
  const ParseResult result = timed_parse("10^6 nested parentheses", "z = " + repeated("(", depth) + "y" + repeated(")", depth));
  EXPECT_EQ(diagnostic_codes(result), "nesting-too-deep");
  EXPECT_EQ(result.diagnostics.items.at(0).message, "expression nested more than 200 levels deep");
  EXPECT_EQ(result.diagnostics.items.at(0).span.begin, 4u + parser::nesting_limit);
}

TEST(Robustness, MillionOpeningBracketsWithoutEnd) {
  EXPECT_EQ(diagnostic_codes(timed_parse("10^6 `[`", "z = " + repeated("[", 1'000'000))), "nesting-too-deep");
  EXPECT_EQ(diagnostic_codes(timed_parse("10^6 `c[`", "z = " + repeated("c[", 1'000'000))), "nesting-too-deep");
}

TEST(Robustness, DeeplyNestedCalls) {
  EXPECT_EQ(diagnostic_codes(timed_parse("10^5 nested calls", "z = " + repeated("sin(", 100'000) + "y" + repeated(")", 100'000))),
            "nesting-too-deep");
}

TEST(Robustness, ChainsOfSignsAndPowers) {
  EXPECT_EQ(diagnostic_codes(timed_parse("10^6 unary minus", "z = " + repeated("-", 1'000'000) + "y")), "nesting-too-deep");
  EXPECT_EQ(diagnostic_codes(timed_parse("10^5 powers", "z = y" + repeated("^y", 100'000))), "nesting-too-deep");
  EXPECT_EQ(diagnostic_codes(timed_parse("10^5 powers of -y", "z = y" + repeated("^-y", 100'000))), "nesting-too-deep");
  // The sign of an exponent is part of its number, and must not hide a chain of `^`.
  EXPECT_EQ(diagnostic_codes(timed_parse("10^5 powers of 1e-1", "z = y" + repeated("^1e-1", 100'000))), "nesting-too-deep");
}

TEST(Robustness, LongFlatChainsAreNotNesting) {
  // `-a*-b*...` and `y^2 + y^2 + ...` recurse only one level at a time.
  const ParseResult products = parse_text("z = " + repeated("-a*", 2000) + "b");
  EXPECT_TRUE(products.diagnostics.items.empty()) << products.diagnostics.render_all();
  const ParseResult powers = parse_text("z = " + repeated("y^2 + ", 2000) + "1");
  EXPECT_TRUE(powers.diagnostics.items.empty()) << powers.diagnostics.render_all();
}

TEST(Robustness, NestingLimitIsExact) {
  const int limit = parser::nesting_limit;
  auto parentheses = [](int depth) { return "z = " + repeated("(", depth) + "y" + repeated(")", depth); };
  EXPECT_TRUE(parse_text(parentheses(limit)).diagnostics.items.empty());
  EXPECT_EQ(diagnostic_codes(parse_text(parentheses(limit + 1))), "nesting-too-deep");
  auto signs = [](int count) { return "z = " + repeated("-", count) + "y"; };
  EXPECT_TRUE(parse_text(signs(limit)).diagnostics.items.empty());
  EXPECT_EQ(diagnostic_codes(parse_text(signs(limit + 1))), "nesting-too-deep");
}

TEST(Robustness, DeepestLegalNestingOfEveryKindParses) {
  // Each wrapper adds the levels noted; together exactly nesting_limit.
  const std::vector<std::pair<std::string, std::string>> wrappers = {
      {"sin(", ")"}, {"(", ")"}, {"c[", "]"}, {"[y < ", "]"}, {"-(", ")"}, {"2^(", ")"}, {"sum(k = 1..2, ", ")"}};
  const std::vector<int> levels = {1, 1, 1, 1, 2, 2, 1};
  std::string open;
  std::string close;
  int depth = 0;
  for (std::size_t i = 0; depth < parser::nesting_limit; ++i) {
    const std::size_t w = i % wrappers.size();
    if (depth + levels[w] > parser::nesting_limit) continue;
    open += wrappers[w].first;
    close = wrappers[w].second + close;
    depth += levels[w];
  }
  const ParseResult result = timed_parse("deepest legal nesting", "z = " + open + "y" + close);
  ASSERT_TRUE(result.diagnostics.items.empty()) << result.diagnostics.render_all().substr(0, 500);
  EXPECT_EQ(result.model.statements.size(), 1u);
}

constexpr std::size_t ten_megabytes = 10'000'000;

TEST(Robustness, TenMegabyteSum) {
  std::string sum(ten_megabytes, '+');
  sum.replace(0, 4, "z = ");
  for (std::size_t i = 4; i < sum.size(); i += 2) sum[i] = 'y';
  EXPECT_EQ(diagnostic_codes(timed_parse("10 MB of y+y+...", std::move(sum))), "statement-too-long");
}

TEST(Robustness, TenMegabyteTokens) {
  std::string name(ten_megabytes, 'a');
  name.replace(0, 4, "z = ");
  EXPECT_EQ(diagnostic_codes(timed_parse("10 MB name", std::move(name))), "statement-too-long");
  std::string number(ten_megabytes, '7');
  number.replace(0, 4, "z = ");
  EXPECT_EQ(diagnostic_codes(timed_parse("10 MB number", std::move(number))), "statement-too-long");
  std::string path(ten_megabytes, 'a');
  path.replace(0, 6, "data \"");
  path.back() = '"';
  EXPECT_EQ(diagnostic_codes(timed_parse("10 MB string", std::move(path))), "statement-too-long");
}

TEST(Robustness, TenMegabytesOfCommentsAndBlankLines) {
  std::string comment(ten_megabytes, 'a');
  comment.replace(0, 2, "# ");
  const ParseResult commented = timed_parse("10 MB comment", comment + "\nz = y");
  EXPECT_TRUE(commented.diagnostics.items.empty());
  EXPECT_EQ(commented.model.statements.size(), 1u);
  const ParseResult blank = timed_parse("10 MB of blank lines", std::string(ten_megabytes, '\n') + "z = y");
  ASSERT_EQ(blank.model.statements.size(), 1u);
  EXPECT_EQ(blank.span(testing::statement_as<ast::Equation>(blank, 0)).start().line, static_cast<int>(ten_megabytes) + 1);
}

TEST(Robustness, LongStatementWithinTheLimitParsesInLinearTime) {
  // 20 000 terms (40 KB); an unoptimised build needs some 0.4 s, an optimised one 0.02 s.
  const std::size_t terms = 20'000;
  const ParseResult result = timed_parse("20 000 terms", "z = y" + repeated("+y", terms - 1));
  ASSERT_TRUE(result.diagnostics.items.empty()) << result.diagnostics.render_all();
  EXPECT_EQ(testing::statement_as<ast::Equation>(result, 0).rhs.rest.size(), terms - 1);
  const ParseResult name = timed_parse("90 KB name", "z = " + std::string(90'000, 'a'));
  EXPECT_EQ(boost::get<ast::Variable>(testing::statement_as<ast::Equation>(name, 0).rhs.first.get()).name.name.size(), 90'000u);
}

TEST(Robustness, ManyStatements) {
  const ParseResult result = timed_parse("1000 equations", repeated("a1*y'' + a2*y = x\n", parser::equation_limit));
  EXPECT_EQ(result.model.statements.size(), parser::equation_limit);
  EXPECT_TRUE(result.diagnostics.items.empty());
}

// The statement and equation limits are exact, and a file of two million one-line equations
// (5.9 GB once built) is refused at the first equation past the limit, without the rest being parsed.
TEST(Robustness, StatementAndEquationLimitsAreExact) {
  const ParseResult at_limit = timed_parse("10 000 statements", repeated("param a\n", parser::statement_limit));
  EXPECT_EQ(at_limit.model.statements.size(), parser::statement_limit);
  EXPECT_TRUE(at_limit.diagnostics.items.empty());
  const ParseResult past_limit = timed_parse("2 000 000 statements", repeated("param a\n", 2'000'000));
  EXPECT_EQ(diagnostic_codes(past_limit), "too-many-statements");
  EXPECT_EQ(past_limit.model.statements.size(), parser::statement_limit);
  ASSERT_EQ(past_limit.diagnostics.items.size(), 1u);
  EXPECT_EQ(past_limit.diagnostics.items[0].span.start().line, static_cast<int>(parser::statement_limit) + 1);

  const ParseResult equations = timed_parse("1 000 equations", repeated("y' = a\n", parser::equation_limit));
  EXPECT_EQ(equations.model.statements.size(), parser::equation_limit);
  EXPECT_TRUE(equations.diagnostics.items.empty());
  const ParseResult millions = timed_parse("2 000 000 equations", repeated("y' = a\n", 2'000'000));
  EXPECT_EQ(diagnostic_codes(millions), "too-many-equations");
  ASSERT_EQ(millions.diagnostics.items.size(), 1u);
  EXPECT_EQ(millions.diagnostics.items[0].span.start().line, static_cast<int>(parser::equation_limit) + 1);
}

TEST(Robustness, MutatedModelsNeverThrowAndPointInsideTheText) {
  const std::string model =
      "model quasi_linear\ninput x = 60*sin(4*pi*t)\noutput y\nparam m, a[1..24]\nconst g = 9.81\n"
      "data \"r.csv\" (t = \"time\", y = y)\nset integrate = 1\n"
      "m*y'' + sum(k = 1..6, a[k]*y'^k)*[y' <= 0 and y > -2] +\n  der(y^3, 1) + int(y) + y'(0) = x\n";
  const std::string alphabet = "()[]\"#;\n^-+*/=<>'.,ab1 \t";
  std::mt19937 random(7);
  for (int round = 0; round < 400; ++round) {
    std::string text = model;
    const int edits = 1 + static_cast<int>(random() % 4);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at = random() % text.size();
      switch (random() % 3) {
        case 0: text.erase(at, 1 + random() % 3); break;
        case 1: text.insert(at, 1, alphabet[random() % alphabet.size()]); break;
        default: text.insert(at, text.substr(random() % text.size(), 1 + random() % 8)); break;
      }
      if (text.empty()) text.push_back('z');
    }
    ParseResult result;
    ASSERT_NO_THROW(result = parse_text(text)) << text;
    expect_spans_inside(result);
    for (const auto& d : result.diagnostics.items) EXPECT_FALSE(d.message.empty());
  }
}

}  // namespace
}  // namespace sidc
