#include "diagnostics/diagnostic.hpp"

#include <algorithm>
#include <fmt/format.h>

namespace sidc {
namespace {

const char* severity_word(Severity s) {
  switch (s) {
    case Severity::error: return "error";
    case Severity::warning: return "warning";
    case Severity::note: return "note";
  }
  return "error";
}

}  // namespace

std::string render(const Diagnostic& d) {
  std::string out;
  if (d.data_file) {
    out = fmt::format("{}:{}:{}: {}: {}", *d.data_file, d.row, d.column, severity_word(d.severity), d.message);
  } else if (d.span.known()) {
    const auto pos = d.span.start();
    out = fmt::format("{}:{}:{}: {}: {}", d.span.file->name, pos.line, pos.column, severity_word(d.severity), d.message);
    // The source line, shortened around the caret when it is very long (a 10 MB line must not
    // flood the terminal).
    const std::string_view line = d.span.file->line_text(pos.line);
    std::size_t first = 0;
    std::size_t col = static_cast<std::size_t>(pos.column - 1);
    if (line.size() > 160 && col > 60) first = col - 60;
    std::string_view shown = line.substr(std::min(first, line.size()), 160);
    std::string text;
    for (char c : shown) text += (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) ? (c == '\t' ? ' ' : '?') : c;
    const std::string number = std::to_string(pos.line);
    const std::string gutter(number.size(), ' ');
    std::size_t caret_at = col - first;
    std::size_t width = std::max<std::size_t>(1, std::min(d.span.length(), text.size() > caret_at ? text.size() - caret_at : 1));
    out += fmt::format("\n {} | {}{}\n {} | {}^{}", number, first ? "..." : "", text, gutter,
                       std::string(caret_at + (first ? 3 : 0), ' '), std::string(width - 1, '~'));
  } else {
    out = fmt::format("{}: {}", severity_word(d.severity), d.message);
  }
  if (!d.hint.empty()) out += fmt::format("\nhint: {}", d.hint);
  return out;
}

bool Diagnostics::has_errors() const {
  return std::any_of(items.begin(), items.end(), [](const Diagnostic& d) { return d.severity == Severity::error; });
}

std::string Diagnostics::render_all() const {
  std::string out;
  for (const auto& d : items) out += render(d) + "\n";
  return out;
}

Diagnostic diag::error(std::string code, const Span& where, std::string message, std::string hint) {
  Diagnostic d;
  d.code = std::move(code);
  d.span = where;
  d.message = std::move(message);
  d.hint = std::move(hint);
  return d;
}

}  // namespace sidc
