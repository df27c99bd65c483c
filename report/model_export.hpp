// The fitted model as code (`sidc export fit.json --as c|python|latex`): the equations with the
// fit's numbers in them, for use outside sidc.
//
// C and Python: a right-hand-side function of the explicit form (ir/explicit_form.hpp, the one
// `sidc simulate` solves): state in, derivatives out, for any ODE integrator. The state is each
// output and its derivatives below the highest (y, y', ..., y^(n-1)), outputs in the model's
// order; a recorded input (and each of its derivatives the equations use) comes in through an
// `inputs` array whose order the generated comment states; an input the model defines
// (`input x = sin(t)`) is written out. Coupled outputs are solved at each call as the runtime
// solves them, a k x k linear system by Gaussian elimination with partial pivoting.
// LaTeX: the derivative form's equations (sum_k a_k op_k = known, eq. 2-1.2) with the numbers in
// place of the parameters, and a table of the values, for a paper.
//
// Relies on: a normalized model and its explicit form (compiler/explicit_form_pass.hpp), values
// indexed like the normalized model's parameters. Guarantees: numbers in shortest round-trip form
// (the C and Python functions compute what sidc computes, to rounding); a model with a quantity
// that only a record defines (an initial value y(0), t0, tau, int(), der()) is a Diagnostic naming
// it, never code that silently differs.
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "ir/explicit_form.hpp"
#include "ir/ir.hpp"

namespace sidc {

enum class ExportLanguage { c, python, latex };

struct ExportRequest {
  const ir::Model& normalized;
  const ExplicitForm& form;
  const std::vector<double>& values;  // per normalized parameter
  std::string origin;                 // where the numbers came from, for the header comment
};

std::variant<std::string, Diagnostic> export_model(const ExportRequest& request, ExportLanguage language);

}  // namespace sidc
