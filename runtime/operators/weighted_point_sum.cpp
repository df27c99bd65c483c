#include "runtime/operators/weighted_point_sum.hpp"

#include <algorithm>
#include <cmath>

namespace sidc {

int WeightedPointSum::base_register(const ir::Factor& f, const ir::Term& t, PointLayout& layout, const PointCompileOptions& options,
                                    std::optional<Diagnostic>& problem) {
  if (auto found = base_of_.find(f); found != base_of_.end()) return found->second;
  const int target = static_cast<int>(registers_.size());
  registers_.push_back(0.0);
  if (f.kind == ir::FactorKind::signal) {
    loads_.push_back({layout.slot(f.name, f.order), target});
  } else {
    // Everything else as PointSum evaluates it: a sum of the one term 1 * f, whose value is f's.
    ir::Term alone;
    alone.span = t.span;  // a diagnostic (int(), der(), an unknown y(0)) points at the term
    alone.factors.emplace_back(f, 1);
    auto compiled = compile_point_sum(ir::Sum{{alone}}, layout, options);
    if (auto* d = std::get_if<Diagnostic>(&compiled)) {
      problem = *d;
      return target;
    }
    compounds_.push_back({std::get<PointSum>(std::move(compiled)), target});
  }
  base_of_.emplace(f, target);
  return target;
}

// PointSum's integer_power: x itself for 1, repeated products for 2..8, std::pow otherwise. x^n is
// x^(n-1) * x, the very product the repeated loop takes last, so one chain gives the same bits.
int WeightedPointSum::power_register(int base, int exponent) {
  if (exponent == 1) return base;
  if (auto found = power_of_.find({base, exponent}); found != power_of_.end()) return found->second;
  const int target = static_cast<int>(registers_.size());
  registers_.push_back(0.0);
  power_of_.emplace(std::make_pair(base, exponent), target);
  if (exponent < 2 || exponent > 8) {
    pows_.push_back({base, exponent, target});
    return target;
  }
  auto chain = std::find_if(chains_.begin(), chains_.end(), [&](const Chain& c) { return c.base == base; });
  if (chain == chains_.end()) chain = chains_.insert(chains_.end(), Chain{base});
  chain->target[static_cast<std::size_t>(exponent)] = target;
  chain->top = std::max(chain->top, exponent);
  return target;
}

std::optional<Diagnostic> WeightedPointSum::add(double weight, int parameter, const ir::Sum& s, PointLayout& layout,
                                                const PointCompileOptions& options) {
  Part part{weight, parameter, static_cast<int>(terms_.size()), static_cast<int>(s.terms.size())};
  for (const ir::Term& t : s.terms) {
    Term term{t.coefficient.value(), static_cast<int>(factors_.size()), static_cast<int>(t.factors.size())};
    for (const auto& [f, exponent] : t.factors) {
      std::optional<Diagnostic> problem;
      const int base = base_register(f, t, layout, options, problem);
      if (problem) return problem;
      const bool guard = f.kind == ir::FactorKind::guard;  // PointSum takes a guard's value as it is
      factors_.push_back({guard ? base : power_register(base, exponent), guard});
    }
    terms_.push_back(term);
  }
  parts_.push_back(part);
  part_values_.push_back(0.0);
  term_values_.assign(terms_.size(), 0.0);
  // The padded layout, rebuilt for all terms so far (add() runs a few dozen times per run).
  width_ = 1;
  exact_terms_.clear();
  for (std::size_t i = 0; i < terms_.size(); ++i) {
    const Term& t = terms_[i];
    const bool guarded = std::any_of(factors_.begin() + t.first, factors_.begin() + t.first + t.count, [](const TermFactor& f) { return f.guard; });
    if (guarded || t.count > 4) exact_terms_.push_back(i);
    else width_ = std::max(width_, t.count);
  }
  if (one_ < 0) {
    one_ = static_cast<int>(registers_.size());
    registers_.push_back(1.0);
  }
  padded_.assign(terms_.size() * static_cast<std::size_t>(width_), one_);
  coefficients_.clear();
  for (const Term& t : terms_) coefficients_.push_back(t.coefficient);
  for (std::size_t i = 0; i < terms_.size(); ++i)
    for (int n = 0; n < terms_[i].count && n < width_; ++n)  // an exact term's own registers unused
      padded_[i * static_cast<std::size_t>(width_) + static_cast<std::size_t>(n)] = factors_[static_cast<std::size_t>(terms_[i].first + n)].reg;
  return std::nullopt;
}

// PointSum::sum's product for one term: a guard that is off zeroes it, and a product that has
// become 0 stays 0 whatever follows (an infinite factor included) unless a factor is NaN.
double WeightedPointSum::exact_term(const Term& t) const {
  const double* r = registers_.data();
  double v = t.coefficient;
  for (int n = t.first; n < t.first + t.count; ++n) {
    const TermFactor& f = factors_[static_cast<std::size_t>(n)];
    const double x = r[f.reg];
    if (f.guard) {
      if (x == 0.0) return 0.0;
      v *= x;
      continue;
    }
    if (v != 0.0 || std::isnan(x)) v *= x;
  }
  return v;
}

namespace {

// coefficient * r[a] * r[b] * ... left to right, `Width` registers per term.
template <int Width>
void plain_products(const double* r, const int* padded, const double* coefficients, std::size_t terms, double* out) {
  for (std::size_t i = 0; i < terms; ++i) {
    double v = coefficients[i];
    for (int n = 0; n < Width; ++n) v *= r[padded[i * Width + static_cast<std::size_t>(n)]];
    out[i] = v;
  }
}

}  // namespace

double WeightedPointSum::evaluate(const PointInstant& at) {
  double* r = registers_.data();
  for (const Load& l : loads_) r[l.target] = at.slots[static_cast<std::size_t>(l.slot)];
  for (const Compound& c : compounds_) r[c.target] = c.factor.evaluate(at);
  for (const Chain& c : chains_) {
    const double x = r[c.base];
    double p = x;
    for (int e = 2; e <= c.top; ++e) {
      p *= x;
      if (const int t = c.target[static_cast<std::size_t>(e)]; t >= 0) r[t] = p;
    }
  }
  for (const Pow& p : pows_) r[p.target] = std::pow(r[p.base], p.exponent);
  double* values = term_values_.data();
  const std::size_t terms = terms_.size();
  const double* c = coefficients_.data();
  switch (width_) {
    case 1: plain_products<1>(r, padded_.data(), c, terms, values); break;
    case 2: plain_products<2>(r, padded_.data(), c, terms, values); break;
    case 3: plain_products<3>(r, padded_.data(), c, terms, values); break;
    default: plain_products<4>(r, padded_.data(), c, terms, values); break;
  }
  for (std::size_t i : exact_terms_) values[i] = exact_term(terms_[i]);
  for (std::size_t i = 0; i < terms; ++i)
    if (std::isnan(values[i])) values[i] = exact_term(terms_[i]);
  double total = 0;
  for (std::size_t k = 0; k < parts_.size(); ++k) {  // PointSum::sum per part, then the weighted sum
    const Part& part = parts_[k];
    double sum = 0;
    for (int i = part.first; i < part.first + part.count; ++i) sum += values[i];
    part_values_[k] = sum;
    total += part.weight * sum;
  }
  return total;
}

}  // namespace sidc
