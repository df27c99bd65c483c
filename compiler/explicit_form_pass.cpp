#include "compiler/explicit_form_pass.hpp"

#include <algorithm>
#include <fmt/format.h>
#include <map>

#include "ir/print.hpp"
#include "ir/traversal.hpp"
#include "diagnostics/model_catalogue.hpp"

namespace sidc {
namespace {

using ir::FactorKind;

std::string derivative_text(const std::string& name, int order) { return name + std::string(static_cast<std::size_t>(order), '\''); }

std::string term_text(const ir::Term& t) { return print(ir::canonical(std::vector<ir::Term>{t})); }

class Builder {
 public:
  explicit Builder(const ir::Model& m) : model_(m) {
    for (const auto& s : m.signals)
      if (s.kind == ir::Signal::Kind::output) {
        index_[s.name] = static_cast<int>(form_.outputs.size());
        form_.outputs.push_back({s.name, 0, s.span});
      }
  }

  std::variant<ExplicitForm, Diagnostic> build() {
    // 1. int() and der() anywhere; each output's order: its highest derivative anywhere.
    std::optional<Diagnostic> problem;
    auto scan = [&](const ir::Term& t) {
      for (const auto& [f, power] : t.factors) {
        if (problem) return;
        if (f.kind == FactorKind::integral) problem = diag::simulate_integral(t.span, term_text(t));
        else if (f.kind == FactorKind::derivative) problem = diag::simulate_estimated_derivative(t.span, term_text(t));
        else if (f.kind == FactorKind::signal) {
          if (auto it = index_.find(f.name); it != index_.end()) {
            auto& o = form_.outputs[static_cast<std::size_t>(it->second)];
            o.order = std::max(o.order, f.order);
          }
        } else if (f.kind == FactorKind::guard) {
          for (const auto& c : f.conditions) add_switching_function(ir::subtract(*c.lhs, *c.rhs));
        } else if (f.kind == FactorKind::function && f.name == "sign") {  // a guard in disguise: it jumps where its argument is 0
          add_switching_function(*f.argument);
        }
      }
    };
    for (const auto& e : model_.equations) {
      for (const auto& p : e.terms) ir::for_each_term(p.operation, scan);
      ir::for_each_term(e.known, scan);
      if (problem) return *problem;
    }
    for (const auto& o : form_.outputs)
      if (o.order == 0) return diag::simulate_static_output(o.span, o.name);
    if (model_.equations.size() != form_.outputs.size())
      return diag::simulate_equation_count(model_.equations.empty() ? model_.name_span : model_.equations.front().span,
                                           model_.equations.size(), form_.outputs.size());

    // 2. Each term into a coefficient of one highest derivative, or into the rest.
    const std::size_t k = form_.outputs.size();
    form_.coefficient.assign(k, std::vector<ParametricSum>(k));
    form_.rest.assign(k, {});
    for (std::size_t i = 0; i < k; ++i) {
      const auto& e = model_.equations[i];
      form_.equation_spans.push_back(e.span);
      for (const auto& p : e.terms)
        for (const auto& t : p.operation.terms)
          if (auto d = place(i, t, p.parameter, 1)) return *d;
      for (const auto& t : e.known.terms)  // sum a_k op_k - known = 0
        if (auto d = place(i, t, -1, -1)) return *d;
    }

    // 3. One equation per highest derivative (augmenting paths; k is small).
    form_.matched.assign(k, -1);
    std::vector<int> equation_of(k, -1);
    for (std::size_t i = 0; i < k; ++i) {
      std::vector<bool> seen(k, false);
      if (!augment(static_cast<int>(i), seen, equation_of)) {
        std::string names;
        for (const auto& o : form_.outputs) names += (names.empty() ? "`" : ", `") + derivative_text(o.name, o.order) + "`";
        return diag::highest_derivatives_unmatched(model_.equations[i].span, names);
      }
    }
    for (std::size_t j = 0; j < k; ++j) form_.matched[static_cast<std::size_t>(equation_of[j])] = static_cast<int>(j);
    return std::move(form_);
  }

 private:
  // The output whose highest derivative factor `f` is, or -1.
  int highest_of(const ir::Factor& f) const {
    if (f.kind != FactorKind::signal) return -1;
    auto it = index_.find(f.name);
    if (it == index_.end()) return -1;
    return form_.outputs[static_cast<std::size_t>(it->second)].order == f.order ? it->second : -1;
  }

  // A highest derivative inside the sum (nested anywhere), for the nonlinear-entry messages.
  std::optional<std::string> highest_inside(const ir::Sum& s) const {
    std::optional<std::string> found;
    ir::for_each_term(s, [&](const ir::Term& t) {
      for (const auto& [f, power] : t.factors)
        if (!found && highest_of(f) >= 0) found = derivative_text(f.name, f.order);
    });
    return found;
  }

  std::optional<Diagnostic> place(std::size_t equation, const ir::Term& t, int parameter, int sign) {
    int which = -1;
    std::size_t at = 0;
    for (std::size_t n = 0; n < t.factors.size(); ++n) {
      const auto& [f, power] = t.factors[n];
      if (const int j = highest_of(f); j >= 0) {
        const std::string d = derivative_text(f.name, f.order);
        if (power != 1) return diag::highest_derivative_nonlinear(t.span, d, fmt::format("to the power {} in `{}`", power, term_text(t)));
        if (which >= 0)
          return diag::highest_derivative_nonlinear(t.span, d, fmt::format("multiplied by another highest derivative in `{}`", term_text(t)));
        which = j;
        at = n;
        continue;
      }
      const char* where = f.kind == FactorKind::function ? "inside a function"
                        : f.kind == FactorKind::power    ? "inside a power"
                        : f.kind == FactorKind::guard    ? "inside a guard"
                                                         : "inside another operation";
      std::optional<std::string> inner;
      ir::for_each_nested_sum(f, [&](const ir::Sum& nested) {
        if (!inner) inner = highest_inside(nested);
      });
      if (inner) return diag::highest_derivative_nonlinear(t.span, *inner, fmt::format("{} in `{}`", where, term_text(t)));
    }
    ir::Term rest = t;
    if (sign < 0) rest.coefficient = -rest.coefficient;
    ParametricSum* target = &form_.rest[equation];
    if (which >= 0) {
      rest.factors.erase(rest.factors.begin() + static_cast<std::ptrdiff_t>(at));
      target = &form_.coefficient[equation][static_cast<std::size_t>(which)];
    }
    const ir::Sum single = ir::canonical(std::vector<ir::Term>{rest});
    if (parameter < 0) {
      target->constant = ir::add(target->constant, single);
      return std::nullopt;
    }
    auto it = std::find_if(target->terms.begin(), target->terms.end(), [&](const ir::ParameterTerm& p) { return p.parameter == parameter; });
    if (it == target->terms.end()) {
      target->terms.push_back({parameter, single});
      std::sort(target->terms.begin(), target->terms.end(), [](const auto& a, const auto& b) { return a.parameter < b.parameter; });
    } else {
      it->operation = ir::add(it->operation, single);
    }
    return std::nullopt;
  }

  bool augment(int equation, std::vector<bool>& seen, std::vector<int>& equation_of) {
    for (std::size_t j = 0; j < form_.outputs.size(); ++j) {
      if (form_.coefficient[static_cast<std::size_t>(equation)][j].empty() || seen[j]) continue;
      seen[j] = true;
      if (equation_of[j] < 0 || augment(equation_of[j], seen, equation_of)) {
        equation_of[j] = equation;
        return true;
      }
    }
    return false;
  }

  void add_switching_function(ir::Sum s) {
    if (s.as_number()) return;  // a constant condition never switches
    if (std::find(form_.switching_functions.begin(), form_.switching_functions.end(), s) == form_.switching_functions.end())
      form_.switching_functions.push_back(std::move(s));
  }

  const ir::Model& model_;
  ExplicitForm form_;
  std::map<std::string, int> index_;
};

}  // namespace

std::variant<ExplicitForm, Diagnostic> explicit_form(const ir::Model& normalized) { return Builder(normalized).build(); }

}  // namespace sidc
