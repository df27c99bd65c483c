#include "ir/traversal.hpp"

namespace sidc::ir {

void for_each_nested_sum(const Factor& f, const std::function<void(const Sum&)>& visit) {
  if (f.argument) visit(*f.argument);
  for (const auto& c : f.conditions) {
    if (c.lhs) visit(*c.lhs);
    if (c.rhs) visit(*c.rhs);
  }
}

bool any_factor(const Sum& s, const std::function<bool(const Factor&)>& holds) {
  for (const auto& t : s.terms)
    for (const auto& [f, power] : t.factors) {
      if (holds(f)) return true;
      bool found = false;
      for_each_nested_sum(f, [&](const Sum& inner) { found = found || any_factor(inner, holds); });
      if (found) return true;
    }
  return false;
}

void for_each_factor(const Sum& s, const std::function<void(const Factor&)>& visit) {
  for (const auto& t : s.terms)
    for (const auto& [f, power] : t.factors) {
      visit(f);
      for_each_nested_sum(f, [&](const Sum& inner) { for_each_factor(inner, visit); });
    }
}

}  // namespace sidc::ir
