// hold_check_pass: no derivative of a held or linear input survives the form passes.
//
// Relies on: declare_pass (each input's hold), integrate_pass and weak_pass (the form the fit will
// evaluate). Guarantees: an input held between samples (`input x held`, zero-order hold) has no
// derivative there but a jump at each sample, and a `linear` one (first-order hold) a derivative
// that jumps; no moving arc can estimate either. In the integrated form an exact antiderivative
// takes `x'` back to `x`, and the weak form moves it onto the test function (int(phi*x') =
// -int(phi'*x), exact for a step), so only what is left after those passes is an error: a
// signal factor of order >= 1, or a der() whose argument holds the input. The check names the
// term and says which form integrates the derivative away.
#pragma once

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"

namespace sidc {

// Adds one diagnostic per offending term; true when there is none.
bool hold_check_pass(const ir::Model& model, Diagnostics& diagnostics);

}  // namespace sidc
