// unit_pass: every parameter's unit, from the units of the signals it multiplies and of its
// equation's parameter-free side (dimensional analysis).
//
// In the linear form sum_k a_k op_k = known (eq. 2-1.2) each a_k must turn its operation's unit
// into the known side's: unit(a_k) = unit(known) / unit(op_k). A derivative divides by the time
// unit, an integral multiplies by it; sin, cos, exp, log and tanh take dimensionless arguments
// (a number factor in the argument carries whatever unit makes it so: `sin(2*pi*t)`), sign() is
// dimensionless whatever its argument, abs() keeps its argument's unit.
//
// Relies on: declare_pass (the signals' units, `set time_unit`; seconds when some signal has a
// unit and no time unit is set), normalize_pass (the linear form). Works on any later form too:
// the integrated and weak forms multiply every term by the same time unit, and integration
// constants get theirs (run again there, it only fills what is still unknown). Guarantees: a model
// that gives no unit is left as it is; where units are given, a term that cannot match its
// equation, a function of a quantity with a unit and a parameter needing two units are errors at
// the term; a parameter whose term holds a signal without a unit, or whose equation has no
// parameter-free side, keeps no unit (nothing to derive it from).
#pragma once

#include <optional>

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"

namespace sidc {

// Sets Parameter::unit where it can be derived and is not set yet; reports what cannot match.
void unit_pass(ir::Model& model, Diagnostics& diagnostics);

}  // namespace sidc
