#include "grammar/statement_scanner.hpp"

#include <vector>

namespace sidc::parser {
namespace {

bool is_name_start(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_name_char(char c) { return is_name_start(c) || is_digit(c); }

// What the previous significant token was; it decides whether a newline continues the
// statement and whether a sign is unary.
enum class Previous { start, operand, continuation, other };

// One past the end of the comment starting at `at` (the position of its `\n`, or text end),
// noting the first invalid byte in it.
std::size_t skip_comment(std::string_view text, std::size_t at, std::optional<std::size_t>& invalid) {
  const char* const data = text.data();
  const std::size_t n = text.size();
  std::size_t i = at;
  while (i < n && data[i] != '\n') {
    const auto byte = static_cast<unsigned char>(data[i]);
    if (byte >= 0x20 && byte < 0x7f) {  // the common case, without a call
      ++i;
      continue;
    }
    const std::size_t length = valid_character_length(text, i);
    if (length == 0 && !invalid) invalid = i;
    i += length == 0 ? 1 : length;
  }
  return i;
}

// After a newline inside brackets: the position of the next significant character when it is a
// closing `)`/`]` (so that the newline continues the statement), else nullopt.
std::optional<std::size_t> closing_after_newline(std::string_view text, std::size_t at,
                                                 std::optional<std::size_t>& invalid) {
  std::optional<std::size_t> invalid_here;
  std::size_t i = at;
  while (i < text.size()) {
    const char c = text[i];
    if (c == ' ' || c == '\t' || c == '\n' || (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n')) {
      ++i;
    } else if (c == '#') {
      i = skip_comment(text, i, invalid_here);
    } else {
      break;
    }
  }
  if (i < text.size() && (text[i] == ')' || text[i] == ']')) {
    if (invalid_here && !invalid) invalid = invalid_here;
    return i;
  }
  return std::nullopt;
}

// One past the end of the number starting at `at`: digits [. digits] [e [+-] digits], or
// . digits [e ...]. The sign of an exponent belongs to the number, not to the expression.
std::size_t skip_number(std::string_view text, std::size_t at) {
  std::size_t i = at;
  while (i < text.size() && is_digit(text[i])) ++i;
  if (i < text.size() && text[i] == '.') {
    ++i;
    while (i < text.size() && is_digit(text[i])) ++i;
  }
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    std::size_t j = i + 1;
    if (j < text.size() && (text[j] == '+' || text[j] == '-')) ++j;
    if (j < text.size() && is_digit(text[j])) {
      while (j < text.size() && is_digit(text[j])) ++j;
      i = j;
    }
  }
  return i;
}

StatementExtent scan_statement(std::string_view text, std::size_t begin) {
  // Written for speed without optimisation too (a 10 MB line must be cut in well under a second
  // in a debug build): raw pointer, no calls in the common paths.
  StatementExtent extent;
  extent.begin = begin;
  const char* const data = text.data();
  const std::size_t n = text.size();

  std::size_t i = begin;
  // `set` statements hold raw text up to the end of the line; brackets and quotes mean nothing.
  const bool setting = text.substr(begin, 3) == "set" && (begin + 3 >= n || !is_name_char(data[begin + 3]));

  Previous previous = Previous::start;
  // Nesting, as the grammar will recurse: `depth` brackets, and in each bracket level the number
  // of unary signs and `^` of the unbroken chain at that level (`chain` for the innermost level,
  // `outer_chains` for the enclosing ones); `total` = depth + all chains.
  std::vector<int> outer_chains;
  int chain = 0;
  long total = 0;

  while (i < n) {
    const char c = data[i];
    if (c == '\n') {
      if (setting) break;
      if (previous == Previous::continuation) {
        ++i;
        continue;
      }
      if (!outer_chains.empty()) {
        if (const auto closing = closing_after_newline(text, i + 1, extent.invalid_byte)) {
          i = *closing;
          continue;
        }
      }
      break;
    }
    if (c == ' ' || c == '\t' || (c == '\r' && i + 1 < n && data[i + 1] == '\n')) {
      ++i;
      continue;
    }
    if (c == ';') {
      if (setting || outer_chains.empty()) break;
      previous = Previous::other;
      ++i;
      continue;
    }
    if (c == '#') {
      i = skip_comment(text, i, extent.invalid_byte);
      continue;
    }
    const auto byte = static_cast<unsigned char>(c);
    if (setting || byte >= 0x80 || byte < 0x20 || byte == 0x7f) {
      const std::size_t length = valid_character_length(text, i);
      if (length == 0 && !extent.invalid_byte) extent.invalid_byte = i;
      i += length == 0 ? 1 : length;
      previous = Previous::operand;
      continue;
    }
    if (is_name_start(c)) {
      const std::size_t start = i;
      ++i;
      while (i < n && is_name_char(data[i])) ++i;
      // `and` (in a guard) and `against` (in a plot statement) join two parts of one statement.
      const std::string_view word(data + start, i - start);
      if (word == "and" || word == "against") {
        total -= chain;
        chain = 0;
        previous = Previous::continuation;
      } else {
        previous = Previous::operand;
      }
      continue;
    }
    if (is_digit(c) || (c == '.' && i + 1 < n && is_digit(data[i + 1]))) {
      i = skip_number(text, i);
      previous = Previous::operand;
      continue;
    }
    bool deeper = false;
    switch (c) {
      case '"':
        ++i;
        while (i < n && data[i] != '"' && data[i] != '\n') {
          const std::size_t length = valid_character_length(text, i);
          if (length == 0 && !extent.invalid_byte) extent.invalid_byte = i;
          i += length == 0 ? 1 : length;
        }
        if (i == n || data[i] == '\n') --i;  // unterminated: the line break ends the statement
        previous = Previous::operand;
        break;
      case '(':
      case '[':
        outer_chains.push_back(chain);
        chain = 0;
        deeper = true;
        previous = Previous::continuation;
        break;
      case ')':
      case ']':
        if (!outer_chains.empty()) {
          total -= 1 + chain;
          chain = outer_chains.back();
          outer_chains.pop_back();
        }
        previous = Previous::operand;
        break;
      case '+':
      case '-':
        if (previous == Previous::operand) {
          total -= chain;
          chain = 0;
        } else {
          ++chain;
          deeper = true;
        }
        previous = Previous::continuation;
        break;
      case '^':
        ++chain;
        deeper = true;
        previous = Previous::continuation;
        break;
      case '*':
      case '/':
      case ',':
      case '=':
        total -= chain;
        chain = 0;
        previous = Previous::continuation;
        break;
      case '<':
      case '>':
        total -= chain;
        chain = 0;
        if (i + 1 < n && data[i + 1] == '=') ++i;
        previous = Previous::continuation;
        break;
      case '\'':
        previous = Previous::operand;
        break;
      default:  // `..`, or a character the grammar will reject
        previous = Previous::other;
        break;
    }
    if (deeper && ++total > nesting_limit && !extent.too_deep_at) extent.too_deep_at = i;
    ++i;
  }
  extent.end = i;
  extent.next = i < n ? i + 1 : n;
  return extent;
}

}  // namespace

std::size_t valid_character_length(std::string_view text, std::size_t at) {
  const auto c = static_cast<unsigned char>(text[at]);
  if (c == '\t' || c == '\n') return 1;
  if (c == '\r') return at + 1 < text.size() && text[at + 1] == '\n' ? 1 : 0;
  if (c < 0x20 || c == 0x7f) return 0;
  if (c < 0x80) return 1;
  // UTF-8 (RFC 3629): no overlong forms, no surrogates, nothing above U+10FFFF.
  std::size_t length = 0;
  unsigned char low = 0x80;
  unsigned char high = 0xbf;
  if (c >= 0xc2 && c <= 0xdf) {
    length = 2;
  } else if (c >= 0xe0 && c <= 0xef) {
    length = 3;
    if (c == 0xe0) low = 0xa0;
    if (c == 0xed) high = 0x9f;
  } else if (c >= 0xf0 && c <= 0xf4) {
    length = 4;
    if (c == 0xf0) low = 0x90;
    if (c == 0xf4) high = 0x8f;
  } else {
    return 0;
  }
  if (at + length > text.size()) return 0;
  const auto second = static_cast<unsigned char>(text[at + 1]);
  if (second < low || second > high) return 0;
  for (std::size_t k = 2; k < length; ++k)
    if ((static_cast<unsigned char>(text[at + k]) & 0xc0) != 0x80) return 0;
  return length;
}

std::optional<StatementExtent> next_statement(std::string_view text, std::size_t from) {
  const char* const data = text.data();
  const std::size_t n = text.size();
  std::size_t i = from;
  // A byte order mark, as some editors write it, is no part of the model.
  if (i == 0 && text.substr(0, 3) == "\xEF\xBB\xBF") i = 3;
  while (i < n) {
    const char c = data[i];
    if (c == ' ' || c == '\t' || c == '\n' || c == ';' || (c == '\r' && i + 1 < n && data[i + 1] == '\n')) {
      ++i;
    } else if (c == '#') {
      std::optional<std::size_t> invalid;
      const std::size_t end = skip_comment(text, i, invalid);
      if (invalid) {
        StatementExtent comment;
        comment.begin = i;
        comment.end = end;
        comment.next = end;
        comment.comment_only = true;
        comment.invalid_byte = invalid;
        return comment;
      }
      i = end;
    } else {
      return scan_statement(text, i);
    }
  }
  return std::nullopt;
}

}  // namespace sidc::parser
