// A model's `plot name(v) = ... against ...` function (ir/ir.hpp PlotFunction) evaluated
// with fitted parameter values over a range of its argument: the reconstructed damper or spring
// of Figs. 4-1.13 and 4-1.14, beside the truth the user supplied.
//
// Relies on: runtime/operators/point_evaluator.hpp (a plot depends on its one argument only, which the
// compiler has checked). Guarantees: `points` equally spaced values of the argument from `low`
// to `high` inclusive; the fitted curve is sum_k a_k op_k(v) + rest(v) with the given values;
// the truth curve is filled only when the model gives one; NaN where a value does not exist
// (a log of a negative number); a Diagnostic only when the function cannot be compiled.
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "ir/ir.hpp"
#include "diagnostics/diagnostic.hpp"

namespace sidc {

struct PlotCurve {
  std::string name;      // the plot's name, e.g. "damper"
  std::string argument;  // e.g. "y'"
  std::vector<double> x, fitted, truth;  // truth empty when the model gives none
};

// `parameters[k]` is the value of model parameter k (Model::parameters order).
std::variant<PlotCurve, Diagnostic> evaluate_plot_function(const ir::PlotFunction& plot, const std::vector<double>& parameters,
                                                           double low, double high, int points = 401);

}  // namespace sidc
