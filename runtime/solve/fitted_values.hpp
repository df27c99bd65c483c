// A fit's estimates laid out by another model's parameter order: the fit solves the integrated
// model, while simulation, validation and pictures use the derivative form (its parameters are
// the same names, without the integration constants), so the estimates are matched by name once,
// here.
#pragma once

#include <vector>

#include "ir/ir.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {

// One value per parameter of `model`: its estimate in `summary`, or `missing` for a parameter the
// fit did not estimate.
std::vector<double> fitted_parameter_values(const ir::Model& model, const FitSummary& summary, double missing);

}  // namespace sidc
