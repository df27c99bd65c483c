// A fit's estimates laid out by another model's parameter order: the fit solves the integrated
// model, while simulation, validation and pictures use the derivative form (its parameters are
// the same parameters first, then the integration constants), so the estimates are laid out once,
// here, by the index each estimate carries.
#pragma once

#include <vector>

#include "ir/ir.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {

// One value per parameter of `model`: its estimate in `summary`, or `missing` for a parameter the
// fit did not estimate.
std::vector<double> fitted_parameter_values(const ir::Model& model, const FitSummary& summary, double missing);

}  // namespace sidc
