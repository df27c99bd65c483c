#include "runtime/solve/switch_quadrature.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "ir/queries.hpp"
#include "runtime/operators/block_evaluator.hpp"
#include "runtime/parallel_ranges.hpp"

namespace sidc {
namespace {

// Where the switch changes value on one sample interval [i, i + 1] of the window.
struct Flip {
  std::size_t i = 0;
  double jump_before = 0, jump_after = 0, rest_before = 0, rest_after = 0;
  double theta = 0;  // the zero of the argument, as a fraction of the interval
};

// True when `rest` vanishes wherever `argument` does (the argument one product, each of whose
// factors the rest has to at least the same power: y' * [y' > 0], y'^2 * sign(y')): the term is
// continuous at the switch, only its slope jumps, and the trapezoid's error there is of order h^2
// already, smaller than what the interpolated switch would change.
bool continuous_at_switch(const ir::Term& rest, const ir::Sum& argument) {
  if (argument.terms.size() != 1 || argument.terms[0].factors.empty()) return false;
  return std::all_of(argument.terms[0].factors.begin(), argument.terms[0].factors.end(), [&](const auto& f) {
    return std::any_of(rest.factors.begin(), rest.factors.end(), [&](const auto& g) { return g.first == f.first && g.second >= f.second; });
  });
}

}  // namespace

std::vector<SwitchedTerm> switched_terms(const ir::Sum& g) {
  std::vector<SwitchedTerm> out;
  for (const auto& t : g.terms) {
    const auto switches = std::count_if(t.factors.begin(), t.factors.end(), [](const auto& f) { return is_switch(f.first); });
    if (switches != 1) continue;
    const auto at = std::find_if(t.factors.begin(), t.factors.end(), [](const auto& f) { return is_switch(f.first); });
    const ir::Factor& s = at->first;
    // sign(a)^2 is not a jump of one sign, and a guard of several conditions may switch on any.
    if (at->second != 1 || (s.kind == ir::FactorKind::guard && s.conditions.size() != 1)) continue;
    ir::Term rest = t;
    rest.factors.erase(rest.factors.begin() + (at - t.factors.begin()));
    const ir::Sum argument = s.kind == ir::FactorKind::guard ? ir::subtract(*s.conditions[0].lhs, *s.conditions[0].rhs) : *s.argument;
    if (continuous_at_switch(rest, argument)) continue;
    out.push_back({ir::canonical(std::vector<ir::Term>{ir::canonical(rest)}), argument, ir::factor(s)});
  }
  return out;
}

std::optional<Diagnostic> add_switch_corrections(Evaluator& evaluator, const TestFunctionGrid& grid, const ir::Sum& g,
                                                 const std::vector<double>& w, std::span<double> out) {
  const std::vector<SwitchedTerm> terms = switched_terms(g);
  if (terms.empty() || evaluator.segmented()) return std::nullopt;
  const FitWindow& window = evaluator.window();
  const std::size_t n = window.size(), m = grid.half_width, count = std::min(grid.centres.size(), out.size());
  std::vector<const ir::Sum*> sums;
  for (const auto& t : terms) sums.insert(sums.end(), {&t.rest, &t.argument, &t.jump});
  auto prepared = prepare_whole_window_values(evaluator.record(), evaluator.model(), evaluator.options(), window, sums);
  if (auto* d = std::get_if<Diagnostic>(&prepared)) return *d;
  const WholeWindowValues& whole = std::get<WholeWindowValues>(prepared);
  constexpr std::size_t kBlock = std::size_t{1} << 15;
  const std::size_t blocks = n > 1 ? (n - 1 + kBlock - 1) / kBlock : 0;
  for (const auto& t : terms) {
    // The intervals where the switch flips, block by block on the blocks' threads (each block one
    // sample longer, for the interval that ends in the next); each block keeps its own, in order.
    std::vector<std::vector<Flip>> found(blocks);
    std::mutex failed;
    std::optional<Diagnostic> structural;
    // Work: three sums a sample, each some tens of operations (a moving arc, a function).
    for_parallel_ranges(blocks, 64 * n, [&](std::size_t b0, std::size_t b1) {
      BlockEvaluator block_evaluator(evaluator.record(), evaluator.options(), window, whole);
      std::vector<double> rest, argument, jump;
      for (std::size_t b = b0; b < b1; ++b) {
        const std::size_t start = b * kBlock, last = std::min(n, start + kBlock + 1);
        for (auto* v : {&rest, &argument, &jump}) v->assign(last - start, 0.0);
        block_evaluator.start_block(window.first + start, window.first + last);
        for (auto [sum, values] : {std::pair{&t.rest, &rest}, std::pair{&t.argument, &argument}, std::pair{&t.jump, &jump}}) {
          auto status = block_evaluator.evaluate(*sum, *values);
          if (auto* d = std::get_if<Diagnostic>(&status)) {
            const std::lock_guard<std::mutex> lock(failed);
            if (!structural) structural = std::move(*d);
            return;
          }
        }
        for (std::size_t a = 0; a + 1 < last - start; ++a) {
          if (jump[a] == jump[a + 1]) continue;
          const double values[] = {rest[a], rest[a + 1], argument[a], argument[a + 1], jump[a], jump[a + 1]};
          if (!std::all_of(std::begin(values), std::end(values), [](double v) { return std::isfinite(v); })) continue;
          const double da = argument[a] - argument[a + 1];
          const double theta = da != 0.0 ? std::clamp(argument[a] / da, 0.0, 1.0) : 0.5;
          found[b].push_back({start + a, jump[a], jump[a + 1], rest[a], rest[a + 1], theta});
        }
      }
    });
    if (structural) return structural;
    std::vector<Flip> flips;
    for (auto& f : found) flips.insert(flips.end(), f.begin(), f.end());
    // Row j's support holds the interval [i, i + 1] when c_j - m <= i and i + 1 <= c_j + m. On it
    // the trapezoid takes (F_0 s_0 + F_1 s_1) / 2 with F = w * rest; with the switch at theta and F
    // linear the integral is s_0 int_0^theta F + s_1 int_theta^1 F, which differs from it by
    // (s_0 - s_1) (F_0 (theta - theta^2/2 - 1/2) + F_1 theta^2/2).
    for (const Flip& f : flips) {
      const auto from = std::lower_bound(grid.centres.begin(), grid.centres.begin() + static_cast<std::ptrdiff_t>(count), f.i + 1 > m ? f.i + 1 - m : 0);
      const auto to = std::upper_bound(from, grid.centres.begin() + static_cast<std::ptrdiff_t>(count), f.i + m);
      for (auto it = from; it != to; ++it) {
        const std::size_t r = f.i + m - *it;  // the interval's first node within the support
        const double F0 = w[r] * f.rest_before, F1 = w[r + 1] * f.rest_after, th = f.theta;
        out[static_cast<std::size_t>(it - grid.centres.begin())] +=
            (f.jump_before - f.jump_after) * (F0 * (th - th * th / 2 - 0.5) + F1 * th * th / 2);
      }
    }
  }
  return std::nullopt;
}

}  // namespace sidc
