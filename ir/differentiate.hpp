// Symbolic time derivatives of IR sums, and partial derivatives with respect to one signal
// derivative: the product rule over factors and the chain rule through the language's functions.
//
// Used by lower_pass (to expand `der(y^3, 1)` into `3*y^2*y'`, eq. 2-2.7 read backwards) and by
// integrate_pass (an antiderivative is accepted only when its derivative reproduces the terms it
// replaces exactly). Returns nullopt where no derivative can be written: guards and sign() jump,
// so `der([y > 0]*y)` is left for the runtime to estimate from the data.
#pragma once

#include <optional>

#include "ir/ir.hpp"
#include "ir/node_budget.hpp"

namespace sidc {

std::optional<ir::Sum> differentiate(const ir::Sum& s, int times = 1);
std::optional<ir::Sum> differentiate(const ir::Term& t);
// As differentiate(s, times), spending the nodes written out of every term it builds from
// `budget`: returns nullopt, with budget.exceeded(), as soon as the budget is spent, so that a
// derivative that grows exponentially (der() of nested functions) stops early.
std::optional<ir::Sum> differentiate(const ir::Sum& s, int times, ir::NodeBudget& budget);

// The partial derivative of `s` with respect to the signal derivative `signal`^(order), every
// other signal derivative, t and the parameters held constant: the Jacobian of a right-hand side,
// as output-error refinement's sensitivity equations need it (runtime/refine/). Guards and sign()
// count as constant (0 between their switches); int() and der() have none (nullopt).
std::optional<ir::Sum> partial_derivative(const ir::Sum& s, const std::string& signal, int order);
// The partial derivative with respect to the parameter factor of index `parameter` (a nonlinear
// parameter, `sin(L*y)` -> `cos(L*y)*y`), signals and t held constant: the refinement's
// sensitivity to it. Guards and sign() hold no parameter (lower_pass refuses it there).
std::optional<ir::Sum> partial_derivative_by_parameter(const ir::Sum& s, int parameter);

// 1/u as a sum: inverted powers for a single term, else the factor (u)^-1.
ir::Sum reciprocal(const ir::Sum& u);
// u^e: expanded for a non-negative integer e (nullopt if more than `max_terms` terms would result,
// or if the terms multiplied on the way overspend `budget`), folded into powers for a single term,
// else the factor (u)^e. When the terms of u are products of independent factors (`y + x + t`),
// u^e has exactly the multinomial count of terms, C(e + n - 1, n - 1) for n terms, and a power
// that would exceed `max_terms` is refused before anything is multiplied.
std::optional<ir::Sum> raise(const ir::Sum& u, const Number& e, std::size_t max_terms = 20000, ir::NodeBudget* budget = nullptr);

}  // namespace sidc
