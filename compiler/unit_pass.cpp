#include "compiler/unit_pass.hpp"

#include <map>
#include <string>

#include "diagnostics/model_catalogue.hpp"
#include "ir/queries.hpp"

namespace sidc {

namespace {

using ir::Unit;

// The unit of IR expressions; nullopt where some factor has none (or a mismatch inside was
// reported: the enclosing expression is then left unchecked, so one mistake makes one error).
class UnitOf {
 public:
  UnitOf(const ir::Model& model, Diagnostics* diagnostics) : model_(model), time_(time_unit(model)), diagnostics_(diagnostics) {}

  std::optional<Unit> sum(const ir::Sum& s, const std::string& parameter = {}) {
    std::optional<Unit> first;
    Span first_at;
    bool unknown = s.empty();
    for (const auto& t : s.terms) {
      const auto u = term(t);
      if (!u) {
        unknown = true;
      } else if (!first) {
        first = u;
        first_at = t.span;
      } else if (!ir::same_dimension(*u, *first)) {
        const Span at = t.span.known() ? t.span : first_at;
        report(parameter.empty() ? diag::unit_mismatch(at, to_string(*u), to_string(*first), first_at)
                                 : diag::operation_unit_mismatch(at, parameter, to_string(*u), to_string(*first), first_at));
        return std::nullopt;
      }
    }
    if (unknown) return std::nullopt;
    return first;
  }

  std::optional<Unit> term(const ir::Term& t) {
    Unit u;
    bool unknown = false;
    for (const auto& [f, p] : t.factors) {
      const auto fu = factor(f, t.span);
      if (!fu) unknown = true;
      else u = ir::multiply(u, ir::power(*fu, Number(p)));
    }
    if (unknown) return std::nullopt;
    return u;
  }

 private:
  std::optional<Unit> factor(const ir::Factor& f, const Span& where) {
    using K = ir::FactorKind;
    switch (f.kind) {
      case K::signal:
      case K::initial_value: {
        const ir::Signal* s = model_.signal(f.name);
        if (!s || !s->unit) return std::nullopt;
        return ir::divide(*s->unit, ir::power(time_, Number(f.order)));
      }
      case K::window_start:
      case K::time:
      case K::elapsed:
        return time_;
      case K::test_function:  // phi is dimensionless; each derivative divides by time
        return ir::power(time_, Number(-f.order));
      case K::function:
        return function(f, where);
      case K::power: {
        const auto b = sum(*f.argument);
        if (!b) return std::nullopt;
        return ir::power(*b, f.exponent);
      }
      case K::derivative: {
        const auto b = sum(*f.argument);
        if (!b) return std::nullopt;
        return ir::divide(*b, ir::power(time_, Number(f.order)));
      }
      case K::integral: {
        const auto b = sum(*f.argument);
        if (!b) return std::nullopt;
        return ir::multiply(*b, time_);
      }
      case K::guard:
        return Unit{};
      case K::parameter:
        return std::nullopt;
    }
    return std::nullopt;
  }

  std::optional<Unit> function(const ir::Factor& f, const Span& where) {
    if (f.name == "sign") {
      sum(*f.argument);  // for the mismatches inside
      return Unit{};
    }
    if (f.name == "abs") return sum(*f.argument);
    if (f.name == "sqrt") {
      const auto b = sum(*f.argument);
      if (!b) return std::nullopt;
      return ir::power(*b, Number::rational(1, 2));
    }
    // sin, cos, exp, log, tanh: a dimensionless argument. A term with a number factor other than
    // +-1 is taken to carry its unit in the number (2*pi*t: 2*pi rad/s times t).
    for (const auto& t : f.argument->terms) {
      const auto u = term(t);
      if (u && !ir::is_dimensionless(*u) && !t.coefficient.abs().is_one()) continue;
      if (u && !ir::is_dimensionless(*u)) {
        report(diag::function_of_unit(t.span.known() ? t.span : where, f.name, to_string(*u)));
        return std::nullopt;
      }
    }
    return Unit{};
  }

  void report(Diagnostic d) {
    if (diagnostics_) diagnostics_->add(std::move(d));
  }

  const ir::Model& model_;
  Unit time_;
  Diagnostics* diagnostics_;
};

}  // namespace

void unit_pass(ir::Model& model, Diagnostics& diagnostics) {
  if (!has_units(model)) return;
  UnitOf unit_of(model, &diagnostics);
  std::map<int, Span> derived_at;  // parameter -> the term its unit came from
  for (auto& e : model.equations) {
    const auto known = unit_of.sum(e.known);
    for (const auto& pt : e.terms) {
      ir::Parameter& p = model.parameters[static_cast<std::size_t>(pt.parameter)];
      const auto op = unit_of.sum(pt.operation, p.name);
      if (!known || !op) continue;
      const Unit u = ir::simplest(ir::divide(*known, *op));
      const Span at = pt.operation.terms.empty() ? e.span : pt.operation.terms.front().span;
      if (!p.unit) {
        p.unit = u;
        derived_at[pt.parameter] = at;
      } else if (!ir::same_dimension(*p.unit, u)) {
        const auto first = derived_at.find(pt.parameter);
        diagnostics.add(diag::parameter_unit_conflict(at, p.name, to_string(u), to_string(*p.unit),
                                                      first == derived_at.end() ? Span{} : first->second));
      }
    }
  }
}

}  // namespace sidc
