#include "compiler/weak_pass.hpp"

#include "compiler/integrate_pass.hpp"

namespace sidc {
namespace {

ir::Sum test_function(int order) {
  return ir::factor(ir::Factor{ir::FactorKind::test_function, "", order, {}, {}, {}, {}});
}

// A term worth moving by parts: it estimates a derivative of the data.
bool estimates_derivative(const ir::Term& t) { return ir::highest_derivative_order(ir::Sum{{t}}) > 0; }

}  // namespace

ir::Sum weak_integrand(const ir::Sum& s, int k) {
  RemainingTerms remaining(s);
  std::vector<ir::Term> result;  // made canonical once: adding term by term was quadratic
  while (!remaining.empty()) {
    const ir::Term t = remaining.front();
    if (estimates_derivative(t)) {
      if (auto antiderivative = exact_antiderivative(t, remaining, false)) {
        // By parts: phi_j^(k) vanishes at both ends of the subdomain, so no boundary term.
        const ir::Sum moved = ir::negate(weak_integrand(*antiderivative, k + 1));
        result.insert(result.end(), moved.terms.begin(), moved.terms.end());
        continue;
      }
    }
    remaining.pop_front();
    const ir::Sum kept = ir::multiply(test_function(k), ir::canonical(std::vector<ir::Term>{t}));
    result.insert(result.end(), kept.terms.begin(), kept.terms.end());
  }
  return ir::canonical(std::move(result));
}

ir::Model weak_pass(ir::Model model, Diagnostics&) {
  for (auto& e : model.equations) {
    if (!e.integration.weak) continue;
    for (auto& term : e.terms) term.operation = weak_integrand(term.operation, 0);
    e.known = weak_integrand(e.known, 0);
    e.weak = true;
    e.integration.weak = false;  // done: the printed model must not ask for it again
  }
  return model;
}

}  // namespace sidc
