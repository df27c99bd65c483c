// normalize_pass: each equation into the form the thesis solves, sum_k a_k * op_k = known.
//
// Relies on: lower_pass (both sides canonical sums; parameters only as plain factors). Guarantees:
// every term holds at most one parameter, to the first power, or it is reported (`a1*a2*y`,
// `a1^2`); each parameter's operation op_k is the canonical sum of what it multiplies, numeric
// factors folded in (eq. 2-1.2); parameter-free terms make up the known side. If the equation had
// all its parameters on the right-hand side, the sides are exchanged so that signs stay as written.
// It reports an equation with no parameter, an equation with no known term (its least-squares
// solution would be all zeros), and two parameters on the same or proportional operations (they are dependent).
// Pinned by tests/golden/normalized/ and tests/golden/bad/.
#pragma once

#include "compiler/lower_pass.hpp"

namespace sidc {

ir::Model normalize_pass(LoweredModel lowered, Diagnostics& diagnostics);

}  // namespace sidc
