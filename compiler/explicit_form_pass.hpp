// explicit_form_pass: the explicit form of a model (ir/explicit_form.hpp): its equations solved for each output's highest derivative, the
// shape an ODE solver needs (thesis section 2-4: "solving the system equation" with the
// determined parameters, eq. 4-1.1 solved for y'').
//
// Relies on: a *normalized* model (CompiledModel::normalized: sum_k a_k op_k = known, eq. 2-1.2,
// before any integration). Knows no data and no parameter values. Guarantees: for outputs
// y_1..y_k of orders n_1..n_k (the highest derivative of each anywhere in the equations), each
// equation i is written as
//     sum_j A_ij * y_j^(n_j) + r_i = 0,
// where A_ij and r_i are linear in the parameters (one Sum per parameter plus a parameter-free
// Sum) and contain no highest derivative; the runtime substitutes parameter values and solves the
// k x k linear system at each instant (k = 1: y^(n) = -r / A). A Diagnostic, with the source span
// of the offending term, when: int() or der() appears, a highest derivative enters nonlinearly
// (a power, a product of two, inside a function, a power of a sum or a guard), an output has no
// derivative (a static model), the number of equations differs from the number of outputs, or no
// assignment of equations to highest derivatives exists (structurally singular A).
// Tests: tests/compiler/explicit_form_test.cpp.
#pragma once

#include <variant>

#include "diagnostics/diagnostic.hpp"
#include "ir/explicit_form.hpp"
#include "ir/ir.hpp"

namespace sidc {

std::variant<ExplicitForm, Diagnostic> explicit_form(const ir::Model& normalized);

}  // namespace sidc
