#include "runtime/solve/fitted_values.hpp"

namespace sidc {

std::vector<double> fitted_parameter_values(const ir::Model& model, const FitSummary& summary, double missing) {
  std::vector<double> values(model.parameters.size(), missing);
  for (const auto& g : summary.groups)
    for (const auto& p : g.summary.parameters)
      if (const int i = model.parameter_index(p.name); i >= 0) values[static_cast<std::size_t>(i)] = p.value;
  return values;
}

}  // namespace sidc
