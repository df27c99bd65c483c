// Test support: parse model text held in a string, and print what came out.
#pragma once

#include <boost/variant/get.hpp>
#include <memory>
#include <string>

#include "grammar/parse.hpp"
#include "tests/grammar/ast_text.hpp"

namespace sidc::testing {

inline ParseResult parse_text(std::string text) {
  return parse_model(std::make_shared<const SourceFile>("model.sid", std::move(text)));
}

// The statements of `text`, one per line as ast_text prints them, followed by the rendered
// diagnostics (so that an unexpected error shows in the failure message).
inline std::string parsed_text(const std::string& text) {
  const ParseResult result = parse_text(text);
  std::string out;
  for (const auto& statement : result.model.statements) out += ast_text::text(statement) + "\n";
  return out + result.diagnostics.render_all();
}

// The only statement of `text`, printed; anything else (several statements, diagnostics) shows.
inline std::string statement_text(const std::string& text) {
  std::string out = parsed_text(text);
  if (!out.empty() && out.back() == '\n') out.pop_back();
  return out;
}

// The codes of the diagnostics of `text`, in order, separated by spaces.
inline std::string diagnostic_codes(const ParseResult& result) {
  std::string out;
  for (const auto& d : result.diagnostics.items) out += (out.empty() ? "" : " ") + d.code;
  return out;
}

template <typename Node>
const Node& statement_as(const ParseResult& result, std::size_t index) {
  return boost::get<Node>(result.model.statements.at(index).get());
}

}  // namespace sidc::testing
