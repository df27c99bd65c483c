// Budgets of symbolic work, counted in IR nodes: a node is a term or a factor.
//
// Expanding sums, powers and products and differentiating nested functions can grow an expression
// without bound from a few characters: 10 nested `sin` differentiated 8 times took 15 s and 650 MB,
// `(y+x+t)^1000000` and sums of sums of 10^9 terms had no end in sight. The compiler therefore
// counts what it builds against two limits (docs/language.md, "Limits"), and each expansion
// predicts what it will cost before it starts where it can (a sum: the product of the ranges; a
// power: the multinomial count of its terms), so that a hopeless one is refused at once:
//   * nodes built: every term and factor made while lowering the model (products, powers, sums,
//     derivatives), the intermediate ones included, which bounds the compiler's time;
//   * nodes written: the lowered model written out in full, where what a function, power, der(),
//     int() or guard holds counts again wherever it stands (the IR shares it; printing and the
//     compiled model do not), which bounds the output and every later pass.
// Relies on nothing but ir.hpp. Guarantees: counting stops as soon as it passes its cap, and
// costs at most the nodes it counts, however deeply the sums nest or are shared.
#pragma once

#include <cstddef>
#include <limits>

#include "ir/ir.hpp"

namespace sidc::ir {

// At most this many nodes built while lowering one model: well under a second of work and
// 256 MB of memory even if every one is kept.
inline constexpr std::size_t kMaxNodesBuilt = 500'000;
// At most this many nodes in the lowered model written out in full, all equations, weights,
// input definitions and plots together: what bounds the compiled model and the later passes.
inline constexpr std::size_t kMaxNodesWritten = 200'000;

// The nodes of `s` (or `t`) written out in full. Counts up to `cap` and returns a value above it
// as soon as the count passes it.
std::size_t written_nodes(const Sum& s, std::size_t cap = std::numeric_limits<std::size_t>::max() - 1);
std::size_t written_nodes(const Term& t, std::size_t cap = std::numeric_limits<std::size_t>::max() - 1);

// A count of nodes against a limit. spend() says whether the budget still holds.
class NodeBudget {
 public:
  explicit NodeBudget(std::size_t limit) : limit_(limit) {}
  bool spend(std::size_t nodes) {
    used_ = nodes > limit_ - std::min(used_, limit_) ? limit_ + 1 : used_ + nodes;
    return !exceeded();
  }
  // Whether `nodes` more would still fit, without spending them (a prediction).
  bool allows(long double nodes) const { return static_cast<long double>(used_) + nodes <= static_cast<long double>(limit_); }
  bool exceeded() const { return used_ > limit_; }
  std::size_t remaining() const { return exceeded() ? 0 : limit_ - used_; }
  std::size_t limit() const { return limit_; }

 private:
  std::size_t limit_;
  std::size_t used_ = 0;
};

}  // namespace sidc::ir
