// The canonical printer: any stage of a model, written back in the language's own syntax.
//
// Deterministic by construction (the IR is canonical; numbers print exactly or in shortest
// round-trip form; parentheses only where precedence needs them), and parseable: printing, then
// parsing, then printing again gives the same text (tests/compiler/print_roundtrip_test.cpp).
#pragma once

#include <string>

#include "ir/ir.hpp"

namespace sidc {

std::string print(const ir::Sum& s);
std::string print(const ir::Term& t);
std::string print(const ir::Factor& f);
// `a1*y'' + a2*y'*y = x`
std::string print(const ir::Equation& e, const ir::Model& m);
// `plot name(y') = ... against ...`, parseable.
std::string print(const ir::PlotFunction& p, const ir::Model& m);
// An equation broken after top-level operators into lines of at most `width` characters, the
// continuation lines indented by `indent` more spaces than the first (which is not indented).
std::string print_wrapped(const ir::Equation& e, const ir::Model& m, std::size_t width = 100, std::size_t indent = 4);
// A whole model file: declarations, settings, data statements and equations.
std::string print(const ir::Model& m);

}  // namespace sidc
