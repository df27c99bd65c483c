#include "runtime/solve/fitted_values.hpp"

namespace sidc {

std::vector<double> fitted_parameter_values(const ir::Model& model, const FitSummary& summary, double missing) {
  std::vector<double> values(model.parameters.size(), missing);
  for (const auto& g : summary.groups)
    for (const auto& p : g.summary.parameters)
      // The fit's model (the integrated one) has the parameters of the derivative form first, in the
      // same order, and its integration constants after them (integrate_pass.cpp); the name check
      // keeps a model of another shape from taking a wrong value.
      if (p.index && !p.index->record && p.index->parameter < values.size() && model.parameters[p.index->parameter].name == p.name)
        values[p.index->parameter] = p.value;
  return values;
}

}  // namespace sidc
