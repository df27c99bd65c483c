#include "compiler/parameter_split.hpp"

#include <fmt/format.h>

#include "diagnostics/model_catalogue.hpp"

namespace sidc {

std::optional<ParameterSplit> split_by_parameter(const ir::Sum& s, const ir::Model& model, Diagnostics& diagnostics) {
  ParameterSplit out;
  bool ok = true;
  for (const auto& t : s.terms) {
    int parameter = -1;
    ir::Term op{t.coefficient, {}, t.span};
    for (const auto& [f, power] : t.factors) {
      // A nonlinear parameter (`sin(L*y)`, `L^2`) stays in the operation, held at a value by the runtime.
      if (f.kind != ir::FactorKind::parameter || model.parameters[static_cast<std::size_t>(f.order)].nonlinear) {
        op.factors.push_back({f, power});
        continue;
      }
      if (power != 1) {
        diagnostics.add(diag::nonlinear_parameter(t.span, f.name, fmt::format("it is raised to the power {}", power)));
        ok = false;
      } else if (parameter >= 0) {
        diagnostics.add(diag::nonlinear_parameter(t.span, f.name,
                                                  fmt::format("it multiplies parameter `{}`", model.parameters[static_cast<std::size_t>(parameter)].name)));
        ok = false;
      }
      parameter = f.order;
    }
    if (parameter < 0) out.rest.push_back(ir::canonical(std::move(op)));
    else out.operations[parameter].push_back(ir::canonical(std::move(op)));
  }
  if (!ok) return std::nullopt;
  return out;
}

}  // namespace sidc
