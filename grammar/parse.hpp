// The grammar's one face: model text in, AST and diagnostics out.
//
// Relies on nothing but the text. Guarantees: it never throws, crashes or hangs on any input
// (empty files, binary bytes, 10^6 nested parentheses, a 10 MB line); every problem becomes a
// Diagnostic with a span; it reports several syntax errors per run by resynchronising at the
// next statement. Nothing here knows what a signal or a parameter is (compiler/declare_pass.cpp, compiler/lower_pass.cpp).
#pragma once

#include <memory>

#include "grammar/ast.hpp"
#include "diagnostics/diagnostic.hpp"
#include "diagnostics/source.hpp"

namespace sidc {

struct ParseResult {
  std::shared_ptr<const SourceFile> source;
  ast::Model model;  // the statements that parsed; those that did not are in `diagnostics`
  Diagnostics diagnostics;
  // Byte ranges of every position_tagged node, indexed by its id_first (see span()).
  std::vector<std::pair<std::size_t, std::size_t>> positions;

  // The span of any node of `model`.
  Span span(const boost::spirit::x3::position_tagged& node) const;
};

ParseResult parse_model(std::shared_ptr<const SourceFile> source);

}  // namespace sidc
