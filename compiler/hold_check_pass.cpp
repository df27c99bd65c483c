#include "compiler/hold_check_pass.hpp"

#include "diagnostics/model_catalogue.hpp"
#include "ir/print.hpp"
#include "ir/traversal.hpp"

namespace sidc {
namespace {

const ir::Signal* piecewise_input(const ir::Model& m, const std::string& name) {
  const ir::Signal* s = m.signal(name);
  return s && s->kind == ir::Signal::Kind::input && s->hold != ir::Signal::Hold::smooth ? s : nullptr;
}

// The first held or linear input `s` mentions, anywhere inside it.
const ir::Signal* mentioned_piecewise_input(const ir::Model& m, const ir::Sum& s) {
  const ir::Signal* found = nullptr;
  ir::walk_factors(s, [&](const ir::Factor& f, const ir::Term&) {
    if (f.kind == ir::FactorKind::signal && (found = piecewise_input(m, f.name))) return ir::Step::stop;
    return ir::Step::into;
  });
  return found;
}

void check(const ir::Model& m, const ir::Sum& s, Diagnostics& diagnostics, bool& fine) {
  ir::walk_factors(s, [&](const ir::Factor& f, const ir::Term& t) {
    const ir::Signal* input = nullptr;
    if (f.kind == ir::FactorKind::signal && f.order > 0) input = piecewise_input(m, f.name);
    else if (f.kind == ir::FactorKind::derivative) input = mentioned_piecewise_input(m, *f.argument);
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
