// The one walk over the IR: every factor of a sum, the factors nested in function, power, der()
// and int() arguments and in guard conditions included, outer before inner.
//
// Passes and evaluators ask questions of a sum ("does it hold a derivative?", "which guards does
// it use?") through these two functions instead of writing their own recursive switch over
// FactorKind, so a new kind of factor is taught to the walk once, here.
#pragma once

#include <functional>

#include "ir/ir.hpp"

namespace sidc::ir {

// Calls `visit` on every factor of `s`, nested factors included, in the canonical order of terms
// and factors, each factor before the factors inside it.
void for_each_factor(const Sum& s, const std::function<void(const Factor&)>& visit);

// True as soon as `holds` is true of some factor of `s`, nested factors included (same order).
bool any_factor(const Sum& s, const std::function<bool(const Factor&)>& holds);

// The sums directly inside a factor: its argument, or both sides of each guard condition.
void for_each_nested_sum(const Factor& f, const std::function<void(const Sum&)>& visit);

}  // namespace sidc::ir
