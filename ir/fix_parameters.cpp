#include "ir/fix_parameters.hpp"

#include <cmath>
#include <limits>

#include "ir/traversal.hpp"

namespace sidc {
namespace {

using ir::Factor;
using ir::FactorKind;
using ir::Sum;

bool has_value(const std::vector<double>& values, int index) {
  return index >= 0 && static_cast<std::size_t>(index) < values.size() && std::isfinite(values[static_cast<std::size_t>(index)]);
}

// The values of the nonlinear parameters only: a linear parameter's entry is never substituted.
std::vector<double> nonlinear_values(const ir::Model& model, const std::vector<double>& values) {
  std::vector<double> out(model.parameters.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < out.size() && k < values.size(); ++k)
    if (model.parameters[k].nonlinear) out[k] = values[k];
  return out;
}

// New index of each parameter after the nonlinear ones are removed (-1 for those).
std::vector<int> renumbering(const ir::Model& model) {
  std::vector<int> index(model.parameters.size(), -1);
  int next = 0;
  for (std::size_t k = 0; k < index.size(); ++k)
    if (!model.parameters[k].nonlinear) index[k] = next++;
  return index;
}

ParametricSum substitute(const ParametricSum& p, const std::vector<double>& values, const std::vector<int>* renumber) {
  ParametricSum out;
  out.constant = substitute_parameters(p.constant, values);
  for (const auto& t : p.terms) {
    const int index = renumber ? (*renumber)[static_cast<std::size_t>(t.parameter)] : t.parameter;
    out.terms.push_back({index, substitute_parameters(t.operation, values)});
  }
  return out;
}

ExplicitForm substitute(const ExplicitForm& form, const std::vector<double>& values, const std::vector<int>* renumber) {
  ExplicitForm out = form;
  for (auto& row : out.coefficient)
    for (auto& c : row) c = substitute(c, values, renumber);
  for (auto& r : out.rest) r = substitute(r, values, renumber);
  for (auto& g : out.switching_functions) g = substitute_parameters(g, values);
  return out;
}

}  // namespace

bool has_nonlinear_parameters(const ir::Model& model) {
  for (const auto& p : model.parameters)
    if (p.nonlinear) return true;
  return false;
}

std::vector<double> nonlinear_guesses(const ir::Model& model) {
  std::vector<double> out(model.parameters.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t k = 0; k < out.size(); ++k)
    if (model.parameters[k].nonlinear && model.parameters[k].guess) out[k] = model.parameters[k].guess->value();
  return out;
}

Sum substitute_parameters(const Sum& s, const std::vector<double>& values) {
  const bool any = ir::any_factor(s, [&](const Factor& f) { return f.kind == FactorKind::parameter && has_value(values, f.order); });
  if (!any) return s;
  Sum out;
  for (const auto& t : s.terms) {
    Sum product = ir::number(t.coefficient, t.span);
    for (const auto& [f, power] : t.factors) {
      if (f.kind == FactorKind::parameter && has_value(values, f.order)) {
        product = ir::scale(product, Number::real(std::pow(values[static_cast<std::size_t>(f.order)], power)));
        continue;
      }
      Factor g = f;
      if (g.argument) g.argument = ir::share(substitute_parameters(*g.argument, values));
      for (auto& c : g.conditions) {
        c.lhs = ir::share(substitute_parameters(*c.lhs, values));
        c.rhs = ir::share(substitute_parameters(*c.rhs, values));
      }
      product = ir::multiply(product, ir::factor(std::move(g), power, t.span));
    }
    out = ir::add(out, product);
  }
  return out;
}

ExplicitForm substitute_nonlinear(const ExplicitForm& form, const ir::Model& model, const std::vector<double>& values) {
  return substitute(form, nonlinear_values(model, values), nullptr);
}

ir::Model fix_nonlinear(const ir::Model& model, const std::vector<double>& values) {
  if (!has_nonlinear_parameters(model)) return model;
  const std::vector<double> held = nonlinear_values(model, values);
  const std::vector<int> renumber = renumbering(model);
  ir::Model out = model;
  for (auto& e : out.equations) {
    for (auto& t : e.terms) {
      t.parameter = renumber[static_cast<std::size_t>(t.parameter)];
      t.operation = substitute_parameters(t.operation, held);
    }
    e.known = substitute_parameters(e.known, held);
  }
  for (auto& p : out.plots) {
    for (auto& t : p.terms) {
      t.parameter = renumber[static_cast<std::size_t>(t.parameter)];
      t.operation = substitute_parameters(t.operation, held);
    }
    p.rest = substitute_parameters(p.rest, held);
  }
  std::erase_if(out.parameters, [](const ir::Parameter& p) { return p.nonlinear; });
  return out;
}

ExplicitForm fix_nonlinear(const ExplicitForm& form, const ir::Model& model, const std::vector<double>& values) {
  if (!has_nonlinear_parameters(model)) return form;
  const std::vector<int> renumber = renumbering(model);
  return substitute(form, nonlinear_values(model, values), &renumber);
}

CompiledModel fix_nonlinear(const CompiledModel& compiled, const std::vector<double>& values) {
  CompiledModel out;
  out.source = compiled.source;
  out.normalized = fix_nonlinear(compiled.normalized, values);
  out.integrated = fix_nonlinear(compiled.integrated, values);
  if (compiled.explicit_form) {
    if (const auto* form = std::get_if<ExplicitForm>(&*compiled.explicit_form)) out.explicit_form = fix_nonlinear(*form, compiled.normalized, values);
    else out.explicit_form = compiled.explicit_form;
  }
  return out;
}

std::vector<double> linear_part(const ir::Model& model, const std::vector<double>& full) {
  std::vector<double> out;
  for (std::size_t k = 0; k < model.parameters.size() && k < full.size(); ++k)
    if (!model.parameters[k].nonlinear) out.push_back(full[k]);
  return out;
}

}  // namespace sidc
