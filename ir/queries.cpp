#include "ir/queries.hpp"

#include <algorithm>

#include "ir/traversal.hpp"

namespace sidc {

int derivative_burden(const ir::Equation& e) {
  int b = ir::highest_derivative_order(e.known);
  for (const auto& p : e.terms) b = std::max(b, ir::highest_derivative_order(p.operation));
  return b;
}

bool is_switch(const ir::Factor& f) {
  return f.kind == ir::FactorKind::guard || (f.kind == ir::FactorKind::function && f.name == "sign");
}

bool is_dynamic(const ir::Sum& s) {
  return ir::any_factor(s, [](const ir::Factor& f) {
    switch (f.kind) {
      case ir::FactorKind::signal: return f.order > 0;
      case ir::FactorKind::time:
      case ir::FactorKind::elapsed:
      case ir::FactorKind::derivative:
      case ir::FactorKind::integral:
      case ir::FactorKind::test_function: return true;
      case ir::FactorKind::parameter:
      case ir::FactorKind::window_start:
      case ir::FactorKind::initial_value: return false;  // constants
      case ir::FactorKind::function:
      case ir::FactorKind::power:
      case ir::FactorKind::guard: return false;  // decided by what they hold
    }
    return false;
  });
}

bool is_static(const ir::Model& model) {
  for (const auto& e : model.equations) {
    if (is_dynamic(e.known)) return false;
    for (const auto& p : e.terms)
      if (is_dynamic(p.operation)) return false;
  }
  return true;
}

const ir::Signal* piecewise_input(const ir::Model& model, const std::string& name) {
  const ir::Signal* s = model.signal(name);
  return s && s->kind == ir::Signal::Kind::input && !s->definition && s->hold != ir::Signal::Hold::smooth ? s : nullptr;
}

const ir::Signal* first_piecewise_input(const ir::Model& model, const ir::Sum& s) {
  const ir::Signal* found = nullptr;
  ir::any_factor(s, [&](const ir::Factor& f) { return f.kind == ir::FactorKind::signal && (found = piecewise_input(model, f.name)) != nullptr; });
  return found;
}

bool has_units(const ir::Model& model) {
  if (model.settings.values.count("time_unit")) return true;
  for (const auto& s : model.signals)
    if (s.unit) return true;
  return false;
}

ir::Unit time_unit(const ir::Model& model) {
  const auto it = model.settings.values.find("time_unit");
  if (it != model.settings.values.end())
    if (auto u = ir::parse_unit(it->second.text)) return *u;  // checked by declare_pass
  ir::Unit seconds;
  seconds.powers.emplace("s", Number(1));
  return seconds;
}

std::string parameter_unit(const ir::Model& model, const std::string& name) {
  const int k = model.parameter_index(name);
  if (k < 0 || !model.parameters[static_cast<std::size_t>(k)].unit) return {};
  return to_string(*model.parameters[static_cast<std::size_t>(k)].unit);
}

}  // namespace sidc
