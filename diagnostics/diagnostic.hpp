// The one shape of every message sidc prints about a user's input.
//
//   model.sid:3:14: error: unknown signal `yy`
//       3 | a1*y'' + a2*yy = x
//         |             ^~
//   hint: did you mean `y`?
//
// Data files use the same shape with row and column (`data.csv:17:3: error: ...`). Wording lives
// in the catalogues (model_catalogue.hpp, data_catalogue.hpp, cli_catalogue.hpp); passes build
// Diagnostics only through them.
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "diagnostics/source.hpp"

namespace sidc {

enum class Severity { error, warning, note };

struct Diagnostic {
  Severity severity = Severity::error;
  std::string code;     // stable identifier, e.g. "unknown-signal"; used by tests and JSON
  Span span;            // where; may be unknown
  std::string message;  // one line, no trailing period
  std::string hint;     // what to do about it; may be empty
  // For data files: an explicit location (file, row, column) instead of a span.
  std::optional<std::string> data_file;
  int row = 0;
  int column = 0;
};

// Renders a diagnostic in the shape above (no trailing newline after the hint line).
std::string render(const Diagnostic& d);

// A list of diagnostics gathered by one phase; phases keep going after an error where they can,
// so that one run reports several problems.
struct Diagnostics {
  std::vector<Diagnostic> items;
  void add(Diagnostic d) { items.push_back(std::move(d)); }
  bool has_errors() const;
  std::string render_all() const;
};

// A whole text file (a model, a compiled model, a fit's parameters), or the Diagnostic naming the
// file and why it cannot be read (diagnostics/cli_catalogue.hpp).
std::variant<std::string, Diagnostic> read_text_file(const std::string& path);
// The same, with the Diagnostic rendered into `error`.
std::optional<std::string> read_whole_file(const std::string& path, std::string& error);

namespace diag {
// An error at `where` with a stable `code`: the one constructor the catalogues build on.
Diagnostic error(std::string code, const Span& where, std::string message, std::string hint = {});
}  // namespace diag

}  // namespace sidc
