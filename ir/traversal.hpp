// The one walk over the IR: every factor of a sum, the factors nested in function, power, der()
// and int() arguments and in guard conditions included, outer before inner.
//
// Passes and evaluators ask questions of a sum ("does it hold a derivative?", "which guards does
// it use?") through these functions instead of writing their own recursive switch over
// FactorKind, so a new kind of factor is taught to the walk once, here (for_each_nested_sum).
// walk_factors() is the general form, for walks that need the term a factor stands in (its span
// names the culprit in a message), leave some nested sums out, or stop at the first answer;
// for_each_factor() and any_factor() are its two common cases. A switch that computes something
// different for each kind (printing, evaluation, differentiation) stays a switch, listing every
// kind so that the compiler points at it when a kind is added.
#pragma once

#include <functional>

#include "ir/ir.hpp"

namespace sidc::ir {

// What walk_factors does after visiting a factor.
enum class Step {
  into,  // go on, into the sums nested in this factor
  over,  // go on, leaving this factor's nested sums out
  stop,  // end the walk
};

// Calls `visit(factor, term)` on every factor of `s` and, where it answers Step::into, on the
// factors nested in it, in the canonical order of terms and factors, each factor before the factors
// inside it; `term` is the term the factor stands in. True when some visit answered Step::stop.
bool walk_factors(const Sum& s, const std::function<Step(const Factor&, const Term&)>& visit);

// Calls `visit` on every factor of `s`, nested factors included (walk_factors' order).
void for_each_factor(const Sum& s, const std::function<void(const Factor&)>& visit);

// True as soon as `holds` is true of some factor of `s`, nested factors included (same order).
bool any_factor(const Sum& s, const std::function<bool(const Factor&)>& holds);

// Calls `visit` on every term of `s`, then on the terms of the sums nested in its factors, term
// by term: a term's own factors are all seen before any factor inside them (the order the explicit
// form reports its first problem in).
void for_each_term(const Sum& s, const std::function<void(const Term&)>& visit);

// The sums directly inside a factor: its argument, or both sides of each guard condition.
void for_each_nested_sum(const Factor& f, const std::function<void(const Sum&)>& visit);

}  // namespace sidc::ir
