// The AST as an indented S-expression, for `sidc compile --dump=ast`: the tree exactly as parsed,
// before any meaning is given to it.
#pragma once

#include <string>

#include "grammar/ast.hpp"

namespace sidc {

std::string print_ast(const ast::Model& model);

}  // namespace sidc
