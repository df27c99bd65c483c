// The grammar's declaration: one rule that reads one statement of a model file.
//
// Relies on grammar/ast.hpp. Guarantees: statement_line() parses exactly one statement extent
// (as cut by grammar/statement_scanner.hpp) into an ast::Statement, or fails with the first
// failed expectation recorded in the context's error handler (grammar/error_handler.hpp). The
// rules are defined in model_def.hpp and instantiated once, in model.cpp.
#pragma once

#include <boost/spirit/home/x3.hpp>

#include "grammar/ast.hpp"

namespace sidc::parser {

namespace x3 = boost::spirit::x3;

struct statement_line_class;
using statement_line_type = x3::rule<statement_line_class, ast::Statement>;
BOOST_SPIRIT_DECLARE(statement_line_type)

}  // namespace sidc::parser

namespace sidc {

parser::statement_line_type const& statement_line();

}  // namespace sidc
