#include "ir/traversal.hpp"

namespace sidc::ir {

void for_each_nested_sum(const Factor& f, const std::function<void(const Sum&)>& visit) {
  if (f.argument) visit(*f.argument);
  for (const auto& c : f.conditions) {
    if (c.lhs) visit(*c.lhs);
    if (c.rhs) visit(*c.rhs);
  }
}

bool walk_factors(const Sum& s, const std::function<Step(const Factor&, const Term&)>& visit) {
  for (const auto& t : s.terms)
    for (const auto& [f, power] : t.factors) {
      const Step step = visit(f, t);
      if (step == Step::stop) return true;
      if (step == Step::over) continue;
      bool stopped = false;
      for_each_nested_sum(f, [&](const Sum& inner) { stopped = stopped || walk_factors(inner, visit); });
      if (stopped) return true;
    }
  return false;
}

void for_each_factor(const Sum& s, const std::function<void(const Factor&)>& visit) {
  walk_factors(s, [&](const Factor& f, const Term&) {
    visit(f);
    return Step::into;
  });
}

bool any_factor(const Sum& s, const std::function<bool(const Factor&)>& holds) {
  return walk_factors(s, [&](const Factor& f, const Term&) { return holds(f) ? Step::stop : Step::into; });
}

void for_each_term(const Sum& s, const std::function<void(const Term&)>& visit) {
  for (const auto& t : s.terms) {
    visit(t);
    for (const auto& [f, power] : t.factors) for_each_nested_sum(f, [&](const Sum& inner) { for_each_term(inner, visit); });
  }
}

}  // namespace sidc::ir
