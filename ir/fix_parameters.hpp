// Nonlinear parameters held at values: `param L = 1.2` inside `sin(L*theta)` made a number.
//
// Linear least squares fits only parameters that multiply an operation (thesis eq. 2-1.8); a
// parameter inside a function, a power or a denominator (ir::Parameter::nonlinear) stays a factor
// of the operations it is in. Before any evaluation, such a parameter is replaced by a value: its
// guess for the equation-error fit, the refinement's current value while it refines. Everything
// that evaluates operations (the fit, instrumental variables, validation, pictures) then sees a
// model linear in its parameters, exactly as if the user had written the number.
//
// Relies on: ir/ir.hpp's canonical arithmetic. Guarantees: substitute_nonlinear keeps every
// parameter index (the runtime's simulation and refinement work in the full parameter list);
// fix_nonlinear removes the substituted parameters from Model::parameters and renumbers the rest,
// so that a fit sees only the parameters it can estimate. No nonlinear parameter factor is left.
#pragma once

#include <vector>

#include "ir/compiled_model.hpp"
#include "ir/explicit_form.hpp"
#include "ir/ir.hpp"

namespace sidc {

bool has_nonlinear_parameters(const ir::Model& model);

// Per parameter of `model`: the guess of each nonlinear parameter, NaN for the others.
std::vector<double> nonlinear_guesses(const ir::Model& model);

// `s` with each parameter factor whose index has a finite value in `values` replaced by it (NaN or
// beyond the vector's end: kept), nested arguments included.
ir::Sum substitute_parameters(const ir::Sum& s, const std::vector<double>& values);

// The explicit form with the nonlinear parameters of `model` at `values` (by parameter index; a
// value for a linear parameter is not used here), every parameter index kept.
ExplicitForm substitute_nonlinear(const ExplicitForm& form, const ir::Model& model, const std::vector<double>& values);

// The model with its nonlinear parameters at `values` and removed from its parameter list (the
// others renumbered in order), and the same for its explicit form.
ir::Model fix_nonlinear(const ir::Model& model, const std::vector<double>& values);
ExplicitForm fix_nonlinear(const ExplicitForm& form, const ir::Model& model, const std::vector<double>& values);
// All three models of a compiled model (normalized, integrated, explicit form) held the same way.
CompiledModel fix_nonlinear(const CompiledModel& compiled, const std::vector<double>& values);

// `full` (one value per parameter of `model`) without its nonlinear parameters' entries: the
// values in fix_nonlinear(model, ...)'s parameter order.
std::vector<double> linear_part(const ir::Model& model, const std::vector<double>& full);

}  // namespace sidc
