// declare_pass: collects the model's declarations and settings from the AST.
//
// Relies on: a parsed model (grammar/parse.hpp). Guarantees: every signal, parameter (families
// expanded to c[1], c[2], ...), constant and data binding is declared once and not under a
// built-in name; every setting is known and has a valid value (docs/language.md, "Settings");
// `integrate` and `constants` are attached to the equations that follow them. Reports each
// problem and goes on. Pinned by tests/golden/bad/.
#pragma once

#include "compiler/declarations.hpp"
#include "grammar/parse.hpp"

namespace sidc {

Declarations declare_pass(const ParseResult& parsed, Diagnostics& diagnostics);

}  // namespace sidc
