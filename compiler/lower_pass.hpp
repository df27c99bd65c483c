// lower_pass: the AST's expressions become canonical IR sums, every name resolved.
//
// Relies on: declare_pass (names are declared once, settings checked). Guarantees: each equation
// side is an ir::Sum with products expanded, powers merged, numbers folded exactly, `sum(...)`
// unrolled, constants substituted, `der(...)` differentiated symbolically where it can be (else
// kept as a derivative factor for the runtime), and `int(...)` split term by term with constant
// factors and parameters taken outside. Parameters appear only as plain factors; a parameter
// inside a function, a guard, a denominator or an exponent is reported here
// (products and powers of parameters by normalize_pass). Without a `param` declaration every
// free name becomes a parameter, in order of appearance. Pinned by tests/golden/normalized/ and
// tests/golden/bad/.
#pragma once

#include "compiler/declarations.hpp"
#include "grammar/parse.hpp"

namespace sidc {

struct LoweredEquation {
  Span span;
  ir::Sum lhs;
  ir::Sum rhs;
  ir::IntegrationRequest integration;
};

struct LoweredModel {
  ir::Model model;  // declarations plus implicit parameters and input definitions
  std::vector<LoweredEquation> equations;
};

LoweredModel lower_pass(Declarations declarations, const ParseResult& parsed, Diagnostics& diagnostics);

// Splits a term into its time-invariant part (coefficient, parameters, t0, initial values) and
// the rest, which is what int() and der() act on.
std::pair<ir::Term, ir::Term> split_constant_part(const ir::Term& t);

// int(s) from t0 to t, linear in s: each term's constant part outside, int(1) = tau (eq. 2-1.4).
ir::Sum integral_of(const ir::Sum& s);

}  // namespace sidc
