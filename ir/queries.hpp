// Questions asked of a compiled model by more than one layer: what estimating its derivatives
// costs, whether it is dynamic at all, and which of its inputs are held between samples. The compiler's integrate_pass chooses the number of
// integrations with them; the runtime sizes derivative margins and decides whether a record needs
// a time column. They live here, beside the IR, so that neither reaches into the other.
#pragma once

#include <string>

#include "ir/ir.hpp"

namespace sidc {

// The highest derivative order anywhere in the equation, inside integrals and functions too.
int derivative_burden(const ir::Equation& e);

// True for a factor that jumps where its argument crosses zero: a guard, or sign() (a guard in
// disguise). The weak form locates its switches, the rows' covariance and a threshold's curvature
// leave it out.
bool is_switch(const ir::Factor& f);

// True when the sum changes with time: a derivative, t, tau, der() or int() anywhere in it.
bool is_dynamic(const ir::Sum& s);

// True when no equation has a derivative, an integral or the time in it: a static regression such
// as NIST's `y = b0 + b1*x`, whose records need no time column.
bool is_static(const ir::Model& model);

// The input `name` when it is recorded and held or linear (`input x held`); nullptr for outputs,
// smooth inputs and inputs given as an expression. compiler/hold_check_pass.cpp rejects their
// derivatives; runtime/operators/piecewise_inputs.hpp integrates them exactly.
const ir::Signal* piecewise_input(const ir::Model& model, const std::string& name);

// The first held or linear input occurring in `s`, inside integrals, functions and guards too; nullptr if none.
const ir::Signal* first_piecewise_input(const ir::Model& model, const ir::Sum& s);

// True when the model gives any unit (a signal's, or `set time_unit`): docs/language.md, "Units".
bool has_units(const ir::Model& model);

// The unit of t: `set time_unit`, else seconds.
ir::Unit time_unit(const ir::Model& model);

// The unit of the parameter `name` as printed beside its estimate (`kg`, `N*s/m`), or "" when the
// model gives it none (or has no such parameter).
std::string parameter_unit(const ir::Model& model, const std::string& name);

}  // namespace sidc
