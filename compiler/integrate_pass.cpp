#include "compiler/integrate_pass.hpp"

#include <algorithm>
#include <stdexcept>
#include <unordered_set>
#include <fmt/format.h>

#include "ir/differentiate.hpp"
#include "ir/queries.hpp"
#include "ir/traversal.hpp"
#include "compiler/lower_pass.hpp"
#include "ir/settings.hpp"
#include "diagnostics/model_catalogue.hpp"

namespace sidc {
namespace {

using ir::Factor;
using ir::FactorKind;
using ir::Sum;
using ir::Term;

// A guard among the term's own factors.
bool has_guard(const Term& t) {
  return std::any_of(t.factors.begin(), t.factors.end(), [](const auto& f) { return f.first.kind == FactorKind::guard; });
}

// F(t0): the antiderivative's value at the start of the fit window, from the record (eq. 4-2.4).
Sum at_window_start(const Sum& s);
std::optional<Sum> factor_at_window_start(const Factor& f) {
  switch (f.kind) {
    case FactorKind::signal: {
      Factor v = Factor::plain(FactorKind::initial_value, f.name, f.order);  // at = nullopt: t0
      return ir::factor(v);
    }
    case FactorKind::time: return ir::factor(Factor::plain(FactorKind::window_start));
    case FactorKind::elapsed:
    case FactorKind::integral: return Sum{};  // both vanish at t0
    case FactorKind::function:
    case FactorKind::power: {
      Factor g = f;
      g.argument = ir::share(at_window_start(*f.argument));
      return ir::factor(g);
    }
    case FactorKind::parameter:
    case FactorKind::window_start:
    case FactorKind::initial_value: return ir::factor(f);
    case FactorKind::derivative:
    case FactorKind::guard:
    case FactorKind::test_function: return std::nullopt;  // no value at t0 in the IR
  }
  return std::nullopt;
}

// True when F(t0) can be written with initial values (signals, time, functions of them).
bool has_value_at_window_start(const Sum& s) {
  return !ir::walk_factors(s, [](const Factor& f, const Term&) {
    if (f.kind == FactorKind::integral) return ir::Step::over;  // vanishes at t0 whatever it holds
    // A function or power is judged by what it holds: asking factor_at_window_start for its
    // value would write out its argument at t0, which throws when that has none.
    if (f.kind == FactorKind::function || f.kind == FactorKind::power) return ir::Step::into;
    return factor_at_window_start(f) ? ir::Step::into : ir::Step::stop;
  });
}
Sum at_window_start(const Sum& s) {
  std::vector<Term> terms;
  for (const auto& t : s.terms) {
    Sum product = ir::number(t.coefficient, t.span);
    for (const auto& [f, power] : t.factors) {
      auto value = factor_at_window_start(f);
      if (!value) throw std::logic_error("an antiderivative without a value at t0 reached at_window_start");
      Sum p = *value;
      Sum raised = ir::number(1);
      if (power > 0) for (int k = 0; k < power; ++k) raised = ir::multiply(raised, p);
      else raised = power == 0 ? ir::number(1) : (p.empty() ? Sum{} : *raise(p, Number(power)));
      product = ir::multiply(product, raised);
    }
    terms.insert(terms.end(), product.terms.begin(), product.terms.end());
  }
  return ir::canonical(std::move(terms));
}

// Takes `t` off `remaining` (matched by factors and coefficient).
bool take(RemainingTerms& remaining, const Term& t) {
  const auto at = remaining.find(t);
  if (at) remaining.take(*at);
  return at.has_value();
}

}  // namespace

RemainingTerms::RemainingTerms(const ir::Sum& canonical_sum) : terms_(canonical_sum.terms), taken_(terms_.size(), false) {}

void RemainingTerms::pop_front() { take(first_); }

void RemainingTerms::take(std::size_t index) {
  taken_[index] = true;
  while (first_ < terms_.size() && taken_[first_]) ++first_;
}

std::optional<std::size_t> RemainingTerms::find(const ir::Term& t) const {
  // A canonical sum is sorted by compare_factors, one term per product of factors.
  const auto it = std::lower_bound(terms_.begin(), terms_.end(), t, [](const Term& a, const Term& b) { return ir::compare_factors(a, b) < 0; });
  if (it == terms_.end() || ir::compare_factors(*it, t) != 0 || !(it->coefficient == t.coefficient)) return std::nullopt;
  const auto index = static_cast<std::size_t>(it - terms_.begin());
  if (taken_[index]) return std::nullopt;
  return index;
}

// An exact antiderivative of `t` whose derivative consists of terms all present in `remaining`
// (t among them); those terms are removed. Candidates lower one derivative of a signal by one
// order: for y^2*y' the candidate y^3 has derivative 3*y^2*y', so y^3/3; for x'*y the candidate
// x*y has derivative x'*y + x*y', accepted only if x*y' is there too.
std::optional<Sum> exact_antiderivative(const Term& t, RemainingTerms& remaining, bool initial) {
  if (has_guard(t)) return std::nullopt;  // its antiderivative changes branch
  auto [constant, rest] = split_constant_part(t);
  // Powers of time alone: t^a -> t^(a+1)/(a+1), tau^b -> tau^(b+1)/(b+1), 1 -> tau.
  if (rest.factors.empty() || (rest.factors.size() == 1 && (rest.factors[0].first.kind == FactorKind::time ||
                                                            rest.factors[0].first.kind == FactorKind::elapsed) &&
                               rest.factors[0].second >= 0)) {
    const FactorKind kind = rest.factors.empty() ? FactorKind::elapsed : rest.factors[0].first.kind;
    const int power = rest.factors.empty() ? 0 : rest.factors[0].second;
    Term p{constant.coefficient / Number(power + 1), constant.factors, t.span};
    p.factors.push_back({Factor::plain(kind), power + 1});
    take(remaining, t);
    return ir::canonical(std::vector<Term>{ir::canonical(p)});
  }
  // int(der(u, k)) = der(u, k-1), and int(der(u, 1)) = u: by definition, whatever u holds.
  if (rest.factors.size() == 1 && rest.factors[0].first.kind == FactorKind::derivative && rest.factors[0].second == 1) {
    const Factor& d = rest.factors[0].first;
    Sum lower = d.order > 1 ? ir::factor(Factor{FactorKind::derivative, "", d.order - 1, {}, {}, d.argument, {}}) : *d.argument;
    // With `constants = initial` the antiderivative's value at t0 must be written out; where it
    // cannot (a derivative or guard inside), the term stays a numerical integral, zero at t0.
    if (initial && !has_value_at_window_start(lower)) return std::nullopt;
    take(remaining, t);
    return ir::multiply(ir::canonical(std::vector<Term>{constant}), lower);
  }
  for (std::size_t i = 0; i < t.factors.size(); ++i) {
    const auto& [f, power] = t.factors[i];
    if (f.kind != FactorKind::signal || f.order < 1 || power < 1) continue;
    Term candidate{Number(1), t.factors, t.span};
    candidate.factors[i].second -= 1;
    Factor lower = f;
    --lower.order;
    candidate.factors.push_back({lower, 1});
    candidate = ir::canonical(candidate);
    auto derivative = differentiate(ir::canonical(std::vector<Term>{candidate}));
    if (!derivative) continue;
    // The term of the derivative that is t itself fixes the scale.
    auto self = std::find_if(derivative->terms.begin(), derivative->terms.end(),
                             [&](const Term& d) { return ir::compare_factors(d, t) == 0; });
    if (self == derivative->terms.end()) continue;
    const Number scale = t.coefficient / self->coefficient;
    const Sum expected = ir::scale(*derivative, scale);
    std::vector<std::size_t> found;  // taken only when every term is there
    for (const auto& d : expected.terms) {
      const auto at = remaining.find(d);
      if (!at) break;
      found.push_back(*at);
    }
    if (found.size() != expected.terms.size()) continue;
    for (std::size_t at : found) remaining.take(at);
    candidate.coefficient = scale;
    return ir::canonical(std::vector<Term>{candidate});
  }
  return std::nullopt;
}

namespace {

struct Integrator {
  ir::Model& model;
  Diagnostics& diagnostics;
  int constants_made = 0;
  // A trial integration (`auto`) only measures what derivatives remain: it makes no constants.
  bool trial = false;
  // The names in use, gathered once: looking each new constant up among 10 000 parameters made
  // a model of as many equations quadratic.
  std::unordered_set<std::string> names_taken;

  std::string next_constant_name() {
    if (names_taken.empty()) {
      for (const auto& p : model.parameters) names_taken.insert(p.name);
      for (const auto& x : model.signals) names_taken.insert(x.name);
      for (const auto& [name, value] : model.constants) names_taken.insert(name);
    }
    std::string name;
    do name = fmt::format("C{}", ++constants_made);
    while (names_taken.count(name));
    names_taken.insert(name);
    return name;
  }

  ir::Equation once(ir::Equation e, std::size_t equation_index) {
    const bool initial = e.integration.constants == ir::IntegrationRequest::Constants::initial;
    for (auto& term : e.terms) term.operation = antiderivative(term.operation, initial);
    e.known = antiderivative(e.known, initial);
    if (!initial && !trial) {  // eq. 2-2.4: the constant of this integration becomes a parameter
      model.parameters.push_back({next_constant_name(), ir::Parameter::Origin::integration_constant, e.span,
                                  static_cast<int>(equation_index), std::nullopt, std::nullopt, false});
      e.terms.push_back({static_cast<int>(model.parameters.size()) - 1, ir::number(1)});
    }
    ++e.integrations;
    return e;
  }

  ir::Equation integrate(const ir::Equation& e, std::size_t index) {
    const auto& r = e.integration;
    const bool dynamic = is_dynamic(e.known) || std::any_of(e.terms.begin(), e.terms.end(),
                                                            [](const ir::ParameterTerm& p) { return is_dynamic(p.operation); });
    if (r.weak) {  // weak_pass's to rewrite, when there is something to integrate
      if (!dynamic) diagnostics.add(diag::static_model_weak(e.span));
      return e;
    }
    int times = r.times;
    if (r.count == ir::IntegrationRequest::Count::automatic) {
      // The smallest N that leaves the fewest derivatives to estimate (4-1.8 -> once, 2-2.6 -> twice).
      const int highest = derivative_burden(e);
      int best = highest;
      times = 0;
      // Without copying the model per equation (quadratic in the equations): a constant's term
      // on a power of tau estimates no derivative, so the trial leaves them out.
      Integrator measure{model, diagnostics, constants_made, true, {}};
      ir::Equation current = e;
      for (int n = 1; n <= std::min(highest, kMaxIntegrations); ++n) {
        current = measure.once(current, index);
        if (const int b = derivative_burden(current); b < best) best = b, times = n;
      }
    }
    if (times > 0 && !dynamic) {
      diagnostics.add(diag::static_model_integrated(e.span, times));
      return e;
    }
    ir::Equation out = e;
    for (int n = 0; n < times; ++n) out = once(out, index);
    // Done: the printed integrated model must not ask for integration again.
    out.integration.count = ir::IntegrationRequest::Count::fixed;
    out.integration.times = 0;
    return out;
  }
};

}  // namespace

Sum antiderivative(const Sum& s, bool initial) {
  RemainingTerms remaining(s);
  std::vector<Term> result;
  while (!remaining.empty()) {
    const Term t = remaining.front();
    if (auto exact = exact_antiderivative(t, remaining, initial)) {
      Sum piece = initial ? ir::subtract(*exact, at_window_start(*exact)) : *exact;
      result.insert(result.end(), piece.terms.begin(), piece.terms.end());
      continue;
    }
    remaining.pop_front();
    const Sum numeric = integral_of(ir::canonical(std::vector<Term>{t}));  // vanishes at t0
    result.insert(result.end(), numeric.terms.begin(), numeric.terms.end());
  }
  return ir::canonical(std::move(result));
}

ir::Model integrate_pass(ir::Model model, const IntegrateOptions& options, Diagnostics& diagnostics) {
  Integrator integrator{model, diagnostics, 0, false, {}};
  std::vector<ir::Equation> equations = model.equations;
  for (std::size_t i = 0; i < equations.size(); ++i) {
    ir::Equation e = equations[i];
    if (options.override_request) {
      const auto constants = e.integration.constants;
      e.integration = *options.override_request;
      e.integration.constants = constants;
    }
    equations[i] = integrator.integrate(e, i);
  }
  model.equations = std::move(equations);
  return model;
}

}  // namespace sidc
