#include "compiler/normalize_pass.hpp"

#include <algorithm>
#include <fmt/format.h>
#include <map>

#include "compiler/parameter_split.hpp"
#include "ir/print.hpp"
#include "ir/traversal.hpp"
#include "diagnostics/model_catalogue.hpp"

namespace sidc {
namespace {

using ir::FactorKind;
using ir::Sum;
using ir::Term;

bool has_parameters(const Sum& s) {
  return std::any_of(s.terms.begin(), s.terms.end(), [](const Term& t) {
    return std::any_of(t.factors.begin(), t.factors.end(), [](const auto& f) { return f.first.kind == FactorKind::parameter; });
  });
}

// A signal or an initial value anywhere, inside functions, der(), int() and guards too.
bool uses_signal(const Sum& s) {
  return ir::any_factor(s, [](const ir::Factor& f) { return f.kind == FactorKind::signal || f.kind == FactorKind::initial_value; });
}

// a = k*b for a number k: two parameters on such operations are as dependent as on equal ones.
bool proportional(const Sum& a, const Sum& b) {
  if (a.terms.size() != b.terms.size() || a.empty()) return false;
  const Number k = a.terms[0].coefficient / b.terms[0].coefficient;
  for (std::size_t i = 0; i < a.terms.size(); ++i)
    if (ir::compare_factors(a.terms[i], b.terms[i]) != 0 || !(a.terms[i].coefficient == k * b.terms[i].coefficient)) return false;
  return true;
}

// The operations proportional to an earlier one, each paired with the first of its kind (i < j),
// in the order of i then j. Only operations with the same products of factors can be proportional:
// sorting by those finds the candidates in n log n, where comparing every pair made 10 000
// parameters take seconds.
std::vector<std::pair<std::size_t, std::size_t>> dependent_pairs(const std::vector<ir::ParameterTerm>& terms) {
  const auto by_factors = [&](std::size_t a, std::size_t b) {
    const Sum& x = terms[a].operation;
    const Sum& y = terms[b].operation;
    if (x.terms.size() != y.terms.size()) return x.terms.size() < y.terms.size();
    for (std::size_t k = 0; k < x.terms.size(); ++k)
      if (int c = ir::compare_factors(x.terms[k], y.terms[k])) return c < 0;
    return false;
  };
  std::vector<std::size_t> order(terms.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), by_factors);
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t begin = 0, end = 0; begin < order.size(); begin = end) {
    end = begin + 1;
    while (end < order.size() && !by_factors(order[begin], order[end])) ++end;
    // Within a run, by the coefficients divided by the first: equal for proportional operations.
    const auto by_ratios = [](const std::vector<Number>& a, const std::vector<Number>& b) {
      return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(), [](const Number& x, const Number& y) { return compare(x, y) < 0; });
    };
    std::map<std::vector<Number>, std::size_t, decltype(by_ratios)> firsts(by_ratios);
    for (std::size_t k = begin; k < end; ++k) {
      const std::size_t j = order[k];
      const Sum& op = terms[j].operation;
      std::vector<Number> ratios;
      for (const auto& t : op.terms) ratios.push_back(t.coefficient / op.terms.front().coefficient);
      const auto [first, inserted] = firsts.emplace(std::move(ratios), j);
      if (!inserted && proportional(terms[first->second].operation, op)) pairs.emplace_back(first->second, j);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace

ir::Model normalize_pass(LoweredModel lowered, Diagnostics& diagnostics) {
  ir::Model model = std::move(lowered.model);
  for (auto& e : lowered.equations) {
    // Exchange sides when the parameters all stand on the right (`y1' = a1*y1 + ...`, eq. 4-2.1).
    const bool swap = !has_parameters(e.lhs) && has_parameters(e.rhs);
    const Sum all = swap ? ir::subtract(e.rhs, e.lhs) : ir::subtract(e.lhs, e.rhs);

    auto split = split_by_parameter(all, model, diagnostics);
    if (!split) continue;

    ir::Equation eq;
    eq.span = e.span;
    eq.integration = e.integration;
    std::vector<Term> known;  // the parameter-free terms, on the other side
    for (const auto& t : split->rest) known.push_back(ir::negate(ir::canonical(std::vector<Term>{t})).terms.front());
    eq.known = ir::canonical(std::move(known));
    for (auto& [parameter, terms] : split->operations) eq.terms.push_back({parameter, ir::canonical(std::move(terms))});
    std::erase_if(eq.terms, [](const ir::ParameterTerm& p) { return p.operation.empty(); });  // a1*y - a1*y

    if (eq.terms.empty()) {
      diagnostics.add(diag::no_parameter(e.span));
      continue;
    }
    if (!uses_signal(all) && !std::any_of(all.terms.begin(), all.terms.end(), [](const Term& t) {
          return std::any_of(t.factors.begin(), t.factors.end(), [](const auto& f) { return f.first.kind != FactorKind::parameter; });
        })) {
      diagnostics.add(diag::no_signal(e.span));
      continue;
    }
    if (eq.known.empty()) {
      diagnostics.add(diag::no_known_term(e.span));
      continue;
    }
    // Two parameters on one operation cannot be told apart.
    for (const auto& [i, j] : dependent_pairs(eq.terms)) {
      const Span& second = eq.terms[j].operation.terms.front().span;
      diagnostics.add(diag::dependent_operations(second.known() ? second : e.span, model.parameters[static_cast<std::size_t>(eq.terms[i].parameter)].name,
                                                 model.parameters[static_cast<std::size_t>(eq.terms[j].parameter)].name,
                                                 print(eq.terms[i].operation)));
    }
    model.equations.push_back(std::move(eq));
  }
  return model;
}

}  // namespace sidc
