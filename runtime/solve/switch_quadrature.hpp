// The weak form's integrals across a switch. A term with sign(a) or a guard [lhs < rhs] jumps
// between two samples, and the trapezoid rule over the samples puts every jump at a sample: an
// error of order h times the integrand at each switch, which does not shrink with the noise (the
// pendulum's Coulomb friction f*sign(y'): 0.36% on a noise-free record of 4,000 samples, 43
// reversals). Each sample interval where such a term's switch changes value is integrated again
// with the switch where its argument (a, or lhs - rhs) crosses zero, located by linear
// interpolation between the two samples, and the rest of the integrand phi^(k) * g linear across
// the interval, as the trapezoid takes it: the error of the location is then of order h^2 and the
// term's integral of order h^3 per switch (the same record: 0.037%).
//
// Relies on: block_evaluator.hpp (the values, block by block on the cores: memory of a block, not
// of the record; the flips found in block order, so the rows are the same on any number of cores),
// test_functions.hpp (the subdomains and phi's quadrature weights). Guarantees: a term
// with exactly one switching factor to the power 1 (sign(), or a guard of one condition) outside
// any integral or function, that jumps there (its other factors do not vanish with the switch's
// argument, as y' * [y' > 0] does), is corrected, every other term is left to the trapezoid; intervals
// with a value that is not finite are left alone (the rows' own evaluation reports those); rows
// of records with held or linear inputs are not touched (they are integrated interval by interval).
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/operators/test_functions.hpp"

namespace sidc {

// A term c * S * M of a sum with one switch S: `rest` = c * M, `argument` = a of sign(a) or
// lhs - rhs of [lhs rel rhs], and `jump` = S alone (its values on the samples: -1, 0, 1 or 0, 1).
struct SwitchedTerm {
  ir::Sum rest, argument, jump;
};

// The terms of `g` whose integral the correction below applies to (empty when there are none).
std::vector<SwitchedTerm> switched_terms(const ir::Sum& g);

// out[j] += the exact-switch integral minus the trapezoid's, of every switched term of `g`
// against row j's test function of weights `w` (test_function_weights for phi's order).
std::optional<Diagnostic> add_switch_corrections(Evaluator& evaluator, const TestFunctionGrid& grid, const ir::Sum& g,
                                                 const std::vector<double>& w, std::span<double> out);

}  // namespace sidc
