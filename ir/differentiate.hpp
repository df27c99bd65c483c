// Symbolic time derivatives of IR sums: the product rule over factors and the chain rule through
// the language's functions.
//
// Used by lower_pass (to expand `der(y^3, 1)` into `3*y^2*y'`, eq. 2-2.7 read backwards) and by
// integrate_pass (an antiderivative is accepted only when its derivative reproduces the terms it
// replaces exactly). Returns nullopt where no derivative can be written: guards and sign() jump,
// so `der([y > 0]*y)` is left for the runtime to estimate from the data.
#pragma once

#include <optional>

#include "ir/ir.hpp"

namespace sidc {

std::optional<ir::Sum> differentiate(const ir::Sum& s, int times = 1);
std::optional<ir::Sum> differentiate(const ir::Term& t);

// 1/u as a sum: inverted powers for a single term, else the factor (u)^-1.
ir::Sum reciprocal(const ir::Sum& u);
// u^e: expanded for a non-negative integer e (nullopt if more than `max_terms` terms would result),
// folded into powers for a single term, else the factor (u)^e.
std::optional<ir::Sum> raise(const ir::Sum& u, const Number& e, std::size_t max_terms = 20000);

}  // namespace sidc
