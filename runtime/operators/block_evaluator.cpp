// Block-by-block evaluation (see block_evaluator.hpp). The arithmetic of every local operation is
// Evaluator's (evaluate.cpp), written out again here on ranges of samples; keep the two in step.
#include "runtime/operators/block_evaluator.hpp"

#include <algorithm>
#include <fmt/format.h>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "ir/print.hpp"
#include "ir/traversal.hpp"
#include "diagnostics/data_catalogue.hpp"
#include "runtime/operators/signal_operator.hpp"
#include "runtime/not_a_number.hpp"

namespace sidc {
namespace {

using ir::FactorKind;

}  // namespace

std::variant<WholeWindowValues, Diagnostic> prepare_whole_window_values(const SampledRecord& record, const ir::Model& model,
                                                                        const EvaluationOptions& options, FitWindow window,
                                                                        const std::vector<const ir::Sum*>& sums) {
  WholeWindowValues whole;
  std::optional<Evaluator> evaluator;  // made only when needed: it caches whole-record vectors
  std::optional<Diagnostic> error;
  for (const ir::Sum* s : sums) {
    // The factors that are not local in time (integrals, initial values), with the span of their
    // term; the local ones are looked into, and what an integral holds is evaluated with it.
    ir::walk_factors(*s, [&](const ir::Factor& f, const ir::Term& t) {
      if (f.kind != FactorKind::integral && f.kind != FactorKind::initial_value) return ir::Step::into;
      const std::string key = print(f);
      if (whole.integrals.count(key) || whole.initial_values.count(key)) return ir::Step::over;
      if (!evaluator) evaluator.emplace(record, model, options, window);
      auto values = evaluator->evaluate(ir::factor(f, 1, t.span));  // 0 + 1 * value: the value itself
      if (auto* d = std::get_if<Diagnostic>(&values)) {
        error = std::move(*d);
        return ir::Step::stop;
      }
      auto& v = std::get<std::vector<double>>(values);
      if (f.kind == FactorKind::initial_value) whole.initial_values[key] = v.empty() ? kNaN : v.front();
      else whole.integrals[key] = std::move(v);
      return ir::Step::over;
    });
    if (error) return *error;
  }
  return whole;
}

BlockEvaluator::BlockEvaluator(const SampledRecord& record, const EvaluationOptions& options, FitWindow window,
                               const WholeWindowValues& whole)
    : record_(record), options_(options), window_(window), whole_(whole) {}

void BlockEvaluator::start_block(std::size_t first, std::size_t last) {
  block_ = {first, std::max(first, last)};
  cache_.clear();
}

const std::string& BlockEvaluator::name_of(const ir::Factor& f) {
  auto it = names_.find(&f);
  if (it == names_.end()) it = names_.emplace(&f, print(f)).first;
  return it->second;
}

std::variant<std::monostate, Diagnostic> BlockEvaluator::evaluate(const ir::Sum& s, std::span<double> out,
                                                                  std::optional<NonFiniteValue>* bad) {
  std::fill(out.begin(), out.end(), 0.0);
  for (std::size_t k = 0; k < s.terms.size(); ++k) {
    auto values = term(s.terms[k], block_);
    if (auto* d = std::get_if<Diagnostic>(&values)) return std::move(*d);
    const Values& v = std::get<Values>(values);
    const std::size_t n = std::min(out.size(), v.size());
    bool finite = true;
    for (std::size_t i = 0; i < n; ++i) {
      out[i] += v[i];
      finite &= std::isfinite(v[i]);
    }
    if (!finite && bad && !*bad) {
      for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(v[i])) {
          *bad = NonFiniteValue{k, block_.first + i};
          break;
        }
    }
  }
  return std::monostate{};
}

std::variant<BlockEvaluator::Values, Diagnostic> BlockEvaluator::sum(const ir::Sum& s, Range r) {
  Values total(r.size(), 0.0);
  for (const auto& t : s.terms) {
    auto values = term(t, r);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    const Values& v = std::get<Values>(values);
    for (std::size_t i = 0; i < total.size(); ++i) total[i] += v[i];
  }
  return total;
}

std::variant<BlockEvaluator::Values, Diagnostic> BlockEvaluator::term(const ir::Term& t, Range r) {
  const std::size_t n = r.size();
  Values v(n, t.coefficient.value());
  for (const auto& [f, power] : t.factors) {
    if (f.kind == FactorKind::guard) {
      auto values = factor(f, t.span, r);
      if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
      const Values& x = *std::get<const Values*>(values);
      // As Evaluator::term: a guard that is off zeroes the term even where the rest has no value.
      for (std::size_t i = 0; i < n; ++i) v[i] = x[i] == 0.0 ? 0.0 : v[i] * x[i];
      continue;
    }
    auto values = power_of(f, power, t.span, r);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    const Values& p = *std::get<const Values*>(values);
    for (std::size_t i = 0; i < n; ++i)
      if (v[i] != 0.0 || std::isnan(p[i])) v[i] *= p[i];
  }
  return v;
}

// f^power on the range: a power ladder for positive integers (f^k = f^(k-1) * f, shared by every
// term that needs any power of f on this block), std::pow otherwise, as Evaluator does.
std::variant<const BlockEvaluator::Values*, Diagnostic> BlockEvaluator::power_of(const ir::Factor& f, int power,
                                                                                const Span& where, Range r) {
  if (power == 1) return factor(f, where, r);
  const auto key = std::tuple{name_of(f), power, r.first, r.last};
  if (auto it = cache_.find(key); it != cache_.end()) return &it->second;
  auto base = factor(f, where, r);
  if (auto* d = std::get_if<Diagnostic>(&base)) return *d;
  const Values& x = *std::get<const Values*>(base);
  Values v(x.size());
  if (power >= 2) {
    auto lower = power_of(f, power - 1, where, r);
    if (auto* d = std::get_if<Diagnostic>(&lower)) return *d;
    const Values& l = *std::get<const Values*>(lower);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = l[i] * x[i];
  } else {
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = std::pow(x[i], power);
  }
  return &(cache_[key] = std::move(v));
}

std::variant<const BlockEvaluator::Values*, Diagnostic> BlockEvaluator::factor(const ir::Factor& f, const Span& where, Range r) {
  const auto key = std::tuple{name_of(f), 1, r.first, r.last};
  if (auto it = cache_.find(key); it != cache_.end()) return &it->second;
  auto values = compute_factor(f, where, r);
  if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
  return &(cache_[key] = std::get<Values>(std::move(values)));
}

std::variant<BlockEvaluator::Values, Diagnostic> BlockEvaluator::compute_factor(const ir::Factor& f, const Span& where, Range r) {
  const std::size_t n = r.size();
  const std::size_t samples = record_.time.size();
  const auto slice = [&](std::span<const double> whole, Range from) {
    return Values(whole.begin() + static_cast<std::ptrdiff_t>(from.first), whole.begin() + static_cast<std::ptrdiff_t>(from.last));
  };
  // The range widened by `m` samples each side, within the record: what a derivative operator
  // reads to give the whole record's values on the range (the whole record when it has no reach).
  const auto widened = [&](std::size_t m) { return Range{r.first > m ? r.first - m : 0, std::min(samples, r.last + m)}; };
  // Values on [r.first, r.last) of an estimate made on `wide`.
  const auto middle = [&](const Values& estimate, Range wide) {
    const auto offset = static_cast<std::ptrdiff_t>(r.first - wide.first);
    return Values(estimate.begin() + offset, estimate.begin() + offset + static_cast<std::ptrdiff_t>(n));
  };
  switch (f.kind) {
    case FactorKind::signal: {
      const auto found = record_.signals.find(f.name);
      if (found == record_.signals.end()) return diag::signal_not_in_record(where, f.name, record_.path);
      if (f.order == 0) return slice(found->second, r);
      const auto op = derivative_operator(options_, f.order, f.name);
      const Range wide = widened(op->reach().value_or(samples));
      const std::span<const double> samples_read(found->second.data() + wide.first, wide.size());
      auto estimate = op->apply(samples_read, record_.step);
      if (auto* d = std::get_if<Diagnostic>(&estimate)) return *d;
      return middle(std::get<Values>(estimate), wide);
    }
    case FactorKind::time: return slice(record_.time, r);
    case FactorKind::elapsed: {
      Values v(n);
      const double t0 = record_.time[window_.first];
      for (std::size_t i = 0; i < n; ++i) v[i] = record_.time[r.first + i] - t0;
      return v;
    }
    case FactorKind::window_start: return Values(n, record_.time[window_.first]);
    case FactorKind::initial_value: {
      const auto found = whole_.initial_values.find(name_of(f));
      if (found == whole_.initial_values.end()) throw std::logic_error("an initial value was not prepared");
      return Values(n, found->second);
    }
    case FactorKind::integral: {
      const auto found = whole_.integrals.find(name_of(f));
      if (found == whole_.integrals.end()) throw std::logic_error("an integral was not prepared");
      const std::size_t from = whole_.integrals_first;
      if (r.first < from || r.last > from + found->second.size()) throw std::logic_error("a block outside the integrals' stretch");
      return slice(found->second, Range{r.first - from, r.last - from});
    }
    case FactorKind::function: {
      auto argument = sum(*f.argument, r);
      if (auto* d = std::get_if<Diagnostic>(&argument)) return *d;
      Values v = std::get<Values>(std::move(argument));
      apply_function(f.name, v);
      return v;
    }
    case FactorKind::power: {
      auto argument = sum(*f.argument, r);
      if (auto* d = std::get_if<Diagnostic>(&argument)) return *d;
      Values v = std::get<Values>(std::move(argument));
      const double e = f.exponent.value();
      for (double& x : v) x = std::pow(x, e);
      return v;
    }
    case FactorKind::derivative: {
      const auto op = derivative_operator(options_, f.order, name_of(f));
      const Range wide = widened(op->reach().value_or(samples));
      auto argument = sum(*f.argument, wide);
      if (auto* d = std::get_if<Diagnostic>(&argument)) return *d;
      auto estimate = op->apply(std::get<Values>(argument), record_.step);
      if (auto* d = std::get_if<Diagnostic>(&estimate)) return *d;
      return middle(std::get<Values>(estimate), wide);
    }
    case FactorKind::guard: {
      Values v(n, 1.0);
      for (const auto& c : f.conditions) {
        auto lhs = sum(*c.lhs, r);
        if (auto* d = std::get_if<Diagnostic>(&lhs)) return *d;
        auto rhs = sum(*c.rhs, r);
        if (auto* d = std::get_if<Diagnostic>(&rhs)) return *d;
        apply_condition(c.relation, std::get<Values>(lhs), std::get<Values>(rhs), v);
      }
      return v;
    }
    case FactorKind::parameter:
    case FactorKind::test_function: break;
  }
  // normalize_pass takes every parameter out of the operations, and the weak form is never
  // streamed (runtime/solve/weak_design.cpp); one here is a bug (exit code 3).
  throw std::logic_error(fmt::format("the factor `{}` reached the block evaluator", print(f)));
}

}  // namespace sidc
