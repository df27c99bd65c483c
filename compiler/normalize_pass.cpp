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
    for (std::size_t i = 0; i < eq.terms.size(); ++i)
      for (std::size_t j = i + 1; j < eq.terms.size(); ++j)
        if (proportional(eq.terms[i].operation, eq.terms[j].operation)) {
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
