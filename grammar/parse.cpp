// parse_model: statement by statement, with resynchronisation and error limits.
//
// Relies on grammar/statement_scanner.hpp to cut the text into statements (and to reject
// invalid bytes, too deep nesting and overlong statements before X3 sees them), and on the X3
// grammar (model.hpp, instantiated in model.cpp) to read one statement. Guarantees: no exception
// leaves parse_model; every statement that fails produces exactly one Diagnostic, worded by
// diagnostics/model_catalogue.hpp, and parsing resumes at the next statement; after
// `error_limit` errors a note ends the list. The spans of the statements that parsed are in
// ParseResult::positions (failed statements leave no entries behind).
#include "grammar/parse.hpp"

#include <algorithm>
#include <array>
#include <exception>
#include <fmt/format.h>
#include <functional>
#include <string_view>

#include "grammar/config.hpp"
#include "diagnostics/model_catalogue.hpp"
#include "grammar/model.hpp"
#include "grammar/statement_scanner.hpp"

namespace sidc {
namespace {

namespace x3 = boost::spirit::x3;
namespace expected = diag::expected;

// More errors than this rarely help: the later ones are often consequences of the first.
constexpr int error_limit = 20;

constexpr std::array<std::string_view, 11> reserved_words = {"model", "input", "output", "param", "const", "data",
                                                             "set",   "and",   "sum",    "der",   "int"};

bool is_name_start(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_name_char(char c) { return is_name_start(c) || is_digit(c); }

bool is_reserved(std::string_view word) {
  return std::find(reserved_words.begin(), reserved_words.end(), word) != reserved_words.end();
}

// The characters the grammar can use outside comments and strings.
bool in_language(unsigned char c) {
  if (c >= 0x80) return false;
  constexpr std::string_view punctuation = " \t\n\r+-*/^()[],=<>'\"#;.";
  return is_name_char(static_cast<char>(c)) || punctuation.find(static_cast<char>(c)) != std::string_view::npos;
}

// Expectations of a name (or of something that may start with one): a reserved word found there
// is reported as such.
bool expects_a_name(std::string_view what) {
  for (std::string_view name : {expected::statement, expected::expression, expected::operand, expected::factor,
                                expected::model_name, expected::signal_name, expected::parameter_name,
                                expected::constant_name, expected::setting_name, expected::sum_index,
                                expected::binding_signal})
    if (what == name) return true;
  return false;
}

// Where the grammar would look next: past blanks, continuation line breaks and comments.
std::size_t skip_white_space(std::string_view text, std::size_t at, std::size_t end) {
  while (at < end) {
    const char c = text[at];
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
      ++at;
    } else if (c == '#') {
      while (at < end && text[at] != '\n') ++at;
    } else {
      break;
    }
  }
  return at;
}

// Length of the token starting at `at` (a name, a number, a string, a two-character operator, or
// one character), within the statement.
std::size_t token_length(std::string_view text, std::size_t at, std::size_t end) {
  std::size_t i = at;
  const char c = text[at];
  if (is_name_start(c)) {
    while (i < end && is_name_char(text[i])) ++i;
  } else if (is_digit(c) || (c == '.' && i + 1 < end && is_digit(text[i + 1]))) {
    while (i < end && is_digit(text[i])) ++i;
    if (i < end && text[i] == '.') {
      ++i;
      while (i < end && is_digit(text[i])) ++i;
    }
    if (i < end && (text[i] == 'e' || text[i] == 'E')) {
      std::size_t j = i + 1;
      if (j < end && (text[j] == '+' || text[j] == '-')) ++j;
      if (j < end && is_digit(text[j])) {
        while (j < end && is_digit(text[j])) ++j;
        i = j;
      }
    }
  } else if (c == '"') {
    ++i;
    while (i < end && text[i] != '"') ++i;
    if (i < end) ++i;
  } else {
    const std::string_view two = text.substr(at, 2);
    i += (two == "<=" || two == ">=" || two == ".." || two == "==") && at + 2 <= end ? 2 : 1;
  }
  return i - at;
}

// A token as a message shows it: in backquotes, shortened when long.
std::string quoted(std::string_view token) {
  constexpr std::size_t longest = 24;
  if (token.size() > longest) return fmt::format("`{}...`", token.substr(0, longest - 4));
  return fmt::format("`{}`", token);
}

// The Diagnostic for a statement X3 did not accept.
Diagnostic diagnose(const ParseResult& result, const parser::StatementExtent& extent,
                    const std::optional<parser::error_handler_type::Failure>& failure,
                    const parser::error_handler_type& handler) {
  const std::string_view text = result.source->text;
  auto span = [&](std::size_t begin, std::size_t end) { return Span{result.source, begin, end}; };

  const std::string which = failure ? failure->which : std::string(expected::statement);
  const std::size_t at =
      skip_white_space(text, failure ? std::min(handler.offset(failure->where), extent.end) : extent.begin, extent.end);

  if (which == expected::closing_quote) {
    const std::size_t line_start = text.rfind('\n', at == 0 ? 0 : at - 1);
    std::size_t quote = text.rfind('"', at == 0 ? 0 : at - 1);
    if (quote == std::string_view::npos || (line_start != std::string_view::npos && quote < line_start)) quote = at;
    return diag::unterminated_string(span(quote, at));
  }

  if (at >= extent.end) {
    std::string found = diag::found::end_of_file;
    if (at < text.size()) found = text[at] == ';' ? "`;`" : diag::found::end_of_line;
    return diag::syntax_expected(span(at, at), which, found);
  }

  const auto byte = static_cast<unsigned char>(text[at]);
  if (!in_language(byte)) {
    const std::size_t length = parser::valid_character_length(text, at);
    if (byte >= 0x80 && length > 1) return diag::non_ascii_character(span(at, at + length), text.substr(at, length));
    return diag::unexpected_character(span(at, at + std::max<std::size_t>(1, length)), byte);
  }

  const std::size_t length = token_length(text, at, extent.end);
  const std::string_view token = text.substr(at, length);
  if (is_name_start(text[at])) {
    if (is_reserved(token) && expects_a_name(which)) return diag::reserved_word_as_name(span(at, at + length), token, which);
    // `parm a1`: a lone word where an equation needed its `=`, close to a statement keyword.
    if (which == expected::equation_equals && is_name_start(text[extent.begin])) {
      std::size_t word_end = extent.begin;
      while (word_end < extent.end && is_name_char(text[word_end])) ++word_end;
      const std::string_view word = text.substr(extent.begin, word_end - extent.begin);
      if (skip_white_space(text, word_end, extent.end) == at) {
        static const std::vector<std::string> statement_keywords = {"model", "input", "output", "param",
                                                                    "const", "data",  "set"};
        const std::string keyword = diag::nearest(word, statement_keywords);
        if (!keyword.empty()) return diag::misspelled_keyword(span(extent.begin, word_end), word, keyword);
      }
    }
  }
  return diag::syntax_expected(span(at, at + length), which, quoted(token));
}

// Reads one statement extent into `result`; returns false when it reported an error.
bool read_statement(ParseResult& result, const parser::StatementExtent& extent) {
  const std::string& text = result.source->text;
  auto span = [&](std::size_t begin, std::size_t end) { return Span{result.source, begin, end}; };

  if (extent.invalid_byte) {
    const std::size_t at = *extent.invalid_byte;
    result.diagnostics.add(diag::unexpected_character(span(at, at + 1), static_cast<unsigned char>(text[at])));
    return false;
  }
  if (extent.too_deep_at) {
    const std::size_t at = *extent.too_deep_at;
    result.diagnostics.add(diag::nesting_too_deep(span(at, at + 1), parser::nesting_limit));
    return false;
  }
  if (extent.end - extent.begin > parser::statement_length_limit) {
    result.diagnostics.add(diag::statement_too_long(span(extent.begin, extent.begin + 1), parser::statement_length_limit));
    return false;
  }

  const std::size_t positions_before = result.positions.size();
  parser::error_handler_type handler(text.cbegin(), result.positions);
  auto first = text.cbegin() + static_cast<std::ptrdiff_t>(extent.begin);
  const auto last = text.cbegin() + static_cast<std::ptrdiff_t>(extent.end);
  ast::Statement statement;
  bool parsed = false;
  try {
    const auto grammar = x3::with<x3::error_handler_tag>(std::ref(handler))[statement_line()];
    parsed = x3::phrase_parse(first, last, grammar, parser::white_space, statement);
  } catch (const x3::expectation_failure<parser::iterator_type>& failure) {
    // statement_line's on_error catches these; kept so that no exception can escape.
    handler.expectation_failed(failure.where(), failure.which());
  } catch (const std::exception& failure) {
    result.positions.resize(positions_before);
    result.diagnostics.add(diag::statement_not_read(span(extent.begin, extent.end), failure.what()));
    return false;
  }
  if (parsed && first == last) {
    result.model.statements.push_back(std::move(statement));
    return true;
  }
  result.positions.resize(positions_before);
  result.diagnostics.add(diagnose(result, extent, handler.failure(), handler));
  return false;
}

void read_statements(ParseResult& result) {
  const std::string_view text = result.source->text;
  int errors = 0;
  std::size_t from = 0, statements = 0, equations = 0;
  while (const auto extent = parser::next_statement(text, from)) {
    from = extent->next;
    if (++statements > parser::statement_limit) {
      result.diagnostics.add(diag::too_many_statements(Span{result.source, extent->begin, extent->begin + 1}, parser::statement_limit));
      return;
    }
    if (errors == error_limit) {
      result.diagnostics.add(diag::too_many_syntax_errors(Span{result.source, extent->begin, extent->begin}, error_limit));
      return;
    }
    if (extent->comment_only) {
      const std::size_t at = *extent->invalid_byte;
      result.diagnostics.add(
          diag::unexpected_character(Span{result.source, at, at + 1}, static_cast<unsigned char>(text[at])));
      ++errors;
      continue;
    }
    if (!read_statement(result, *extent)) {
      ++errors;
    } else if (boost::get<ast::Equation>(&result.model.statements.back().get()) && ++equations > parser::equation_limit) {
      result.diagnostics.add(diag::too_many_equations(Span{result.source, extent->begin, extent->begin + 1}, parser::equation_limit));
      return;
    }
  }
}

}  // namespace

Span ParseResult::span(const boost::spirit::x3::position_tagged& node) const {
  if (node.id_first < 0 || static_cast<std::size_t>(node.id_first) >= positions.size()) return Span{};
  const auto& [begin, end] = positions[static_cast<std::size_t>(node.id_first)];
  return Span{source, begin, end};
}

ParseResult parse_model(std::shared_ptr<const SourceFile> source) {
  ParseResult result;
  result.source = std::move(source);
  if (!result.source) return result;
  try {
    read_statements(result);
  } catch (const std::exception& failure) {
    // Only memory exhaustion can get here; report it on the file rather than crash.
    try {
      result.diagnostics.add(diag::statement_not_read(Span{result.source, 0, 0}, failure.what()));
    } catch (...) {
    }
  }
  return result;
}

}  // namespace sidc
