// Where each statement of a model file begins and ends, found before Spirit X3 sees it.
//
// Relies on nothing but the bytes. Guarantees, in one linear pass that never recurses:
//   * the extent of every statement, by the line rules of docs/language.md (a statement ends at
//     a newline or at `;` outside brackets; it continues after a newline that follows an
//     operator, `(`, `[`, `,`, `=`, a comparison or `and`, or that precedes a closing `)`/`]`;
//     a `set` statement always ends at its line's end or `;`). The X3 grammar then parses one
//     extent at a time with newlines as plain white space, so the line rules live only here;
//   * the first byte that can never appear in a model (control characters, NUL, a lone CR,
//     invalid UTF-8), comments and strings included;
//   * a bound on how deep X3 would recurse on the statement: every `(`/`[` counts one level,
//     and so does every `^` and every unary sign of an unbroken chain (`y^y^y`, `- - y`), since
//     those recurse too. A statement deeper than `nesting_limit` is rejected before X3 runs,
//     so that 10^6 nested parentheses cannot exhaust the stack.
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>

namespace sidc::parser {

// Deepest nesting the parser accepts (see the file comment for what counts as one level), far
// above any model written by hand. Each level costs X3 a dozen or more stack frames: 200 levels
// of the costliest kinds (guards, sums) were measured to need about 0.5 MB of stack in an
// optimised build, 1.5 MB unoptimised and 3 MB with the sanitizers, against the usual 8 MB of
// the main thread. Parsing on a thread with a smaller stack needs a smaller limit.
inline constexpr int nesting_limit = 200;

// Longest statement the parser accepts, in bytes. The thesis' longest equation is under a
// kilobyte; the limit bounds the worst case (one statement of 50 000 terms) to a fraction of a
// second even in an unoptimised build, where X3 runs some twenty times slower than optimised.
// A longer statement is reported, not parsed.
inline constexpr std::size_t statement_length_limit = 100'000;

// Most statements a model file may hold. Checked while the statements are cut, before any is
// parsed, so that a file of millions of one-line equations is refused in a blink instead of being
// built into trees first (2 000 000 one-line equations took 5.9 GB). The thesis' largest model has
// a few dozen statements; families and sums write large models in few statements.
inline constexpr std::size_t statement_limit = 10'000;
// Most equations a model may hold, checked as each is parsed. Every equation costs the later
// passes and the compiled model some 3 KB (10 000 one-line equations made a 29 MB file, 220 MB of
// memory and seconds of work); a thousand keep any model well under a second and 256 MB.
inline constexpr std::size_t equation_limit = 1'000;

struct StatementExtent {
  std::size_t begin = 0;  // first character of the statement (after blanks and comments)
  std::size_t end = 0;    // one past its last character: the terminating `\n`/`;`, or text end
  std::size_t next = 0;   // where the following statement's search starts
  // Not a statement but a comment line holding an invalid byte: report it and go on.
  bool comment_only = false;
  std::optional<std::size_t> invalid_byte;  // first byte that cannot appear in a model file
  std::optional<std::size_t> too_deep_at;   // where the nesting first exceeded nesting_limit
};

// The next statement at or after `from`, skipping blank lines, comment lines, empty statements
// (`;;`) and a UTF-8 byte order mark at the start of the text. Returns nullopt when only blanks
// and comments remain.
std::optional<StatementExtent> next_statement(std::string_view text, std::size_t from);

// Length of the character starting at `at` when it may appear in a model file (in a comment or
// a string, any valid UTF-8; elsewhere the grammar decides), or 0 when it never may: NUL and
// other control characters except tab, newline and a CR that ends a line; DEL; invalid UTF-8.
std::size_t valid_character_length(std::string_view text, std::size_t at);

}  // namespace sidc::parser
