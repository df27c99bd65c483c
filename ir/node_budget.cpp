#include "ir/node_budget.hpp"

#include <algorithm>
#include <unordered_map>

namespace sidc::ir {
namespace {

// Counts with a memo of the nested sums already counted: a sum shared by many factors (the IR
// shares arguments) is walked once, so the count costs no more than the sums actually held.
struct Counter {
  std::size_t cap;
  std::unordered_map<const Sum*, std::size_t> seen;

  std::size_t add(std::size_t a, std::size_t b) const { return a > cap || b > cap - std::min(a, cap) ? cap + 1 : a + b; }

  std::size_t nested(const SumPtr& s) {
    if (!s) return 0;
    if (auto it = seen.find(s.get()); it != seen.end()) return it->second;
    const std::size_t n = sum(*s);
    seen.emplace(s.get(), n);
    return n;
  }

  std::size_t term(const Term& t) {
    std::size_t n = 1;
    for (const auto& [f, power] : t.factors) {
      n = add(n, 1);
      n = add(n, nested(f.argument));
      for (const auto& c : f.conditions) n = add(add(n, nested(c.lhs)), nested(c.rhs));
      if (n > cap) return n;
    }
    return n;
  }

  std::size_t sum(const Sum& s) {
    std::size_t n = 0;
    for (const auto& t : s.terms) {
      n = add(n, term(t));
      if (n > cap) return n;
    }
    return n;
  }
};

}  // namespace

std::size_t written_nodes(const Sum& s, std::size_t cap) { return Counter{cap, {}}.sum(s); }
std::size_t written_nodes(const Term& t, std::size_t cap) { return Counter{cap, {}}.term(t); }

}  // namespace sidc::ir
