#include "compiler/hold_check_pass.hpp"

#include "diagnostics/model_catalogue.hpp"
#include "ir/queries.hpp"
#include "ir/print.hpp"
#include "ir/traversal.hpp"

namespace sidc {
namespace {

void check(const ir::Model& m, const ir::Sum& s, Diagnostics& diagnostics, bool& fine) {
  ir::walk_factors(s, [&](const ir::Factor& f, const ir::Term& t) {
    const ir::Signal* input = nullptr;
    if (f.kind == ir::FactorKind::signal && f.order > 0) input = piecewise_input(m, f.name);
    else if (f.kind == ir::FactorKind::derivative) input = first_piecewise_input(m, *f.argument);
    if (!input) return ir::Step::into;
    diagnostics.add(diag::derivative_of_held_input(t.span.known() ? t.span : input->hold_span, input->name, to_string(input->hold), print(f)));
    fine = false;
    return ir::Step::over;
  });
}

}  // namespace

bool hold_check_pass(const ir::Model& model, Diagnostics& diagnostics) {
  bool fine = true;
  for (const auto& e : model.equations) {
    check(model, e.known, diagnostics, fine);
    for (const auto& p : e.terms) check(model, p.operation, diagnostics, fine);
  }
  if (model.weights) check(model, model.weights->value, diagnostics, fine);
  return fine;
}

}  // namespace sidc
