#include "compiler/lower_pass.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <set>
#include <unordered_map>

#include "ir/differentiate.hpp"
#include "ir/node_budget.hpp"
#include "ir/traversal.hpp"
#include "compiler/parameter_split.hpp"
#include "ir/print.hpp"
#include "ir/settings.hpp"
#include "diagnostics/model_catalogue.hpp"

namespace sidc {

using ir::Factor;
using ir::FactorKind;
using ir::Sum;
using ir::Term;

std::pair<Term, Term> split_constant_part(const Term& t) {
  Term constant{t.coefficient, {}, t.span}, rest{Number(1), {}, t.span};
  for (const auto& item : t.factors) {
    const bool constant_in_time = item.first.kind == FactorKind::parameter || item.first.is_constant_in_time();
    (constant_in_time ? constant : rest).factors.push_back(item);
  }
  return {ir::canonical(constant), ir::canonical(rest)};
}

Sum integral_of(const Sum& s) {
  std::vector<Term> terms;
  for (const auto& t : s.terms) {
    auto [constant, rest] = split_constant_part(t);
    if (rest.factors.empty()) {  // int(1) = tau: the integral from t0 of a constant
      rest.factors.push_back({Factor{FactorKind::elapsed, "", 0, {}, {}, {}, {}}, 1});
    } else {
      Factor f{FactorKind::integral, "", 0, {}, {}, ir::share(ir::canonical(std::vector<Term>{rest})), {}};
      rest = Term{Number(1), {{f, 1}}, t.span};
    }
    terms.push_back(ir::multiply(constant, rest));
  }
  return ir::canonical(std::move(terms));
}

namespace {

constexpr std::size_t kMaxTerms = 20000;

// What an expression may refer to where it stands.
struct Context {
  bool parameters = false;  // equations
  bool signals = false;     // equations
  bool time = false;        // equations and input definitions
  const char* what = "";    // for "... must be a number": "a constant", "an index"
  std::string input;        // the input being defined, for its diagnostic
  std::string known_only;   // "the weights": where a parameter may not stand, for its diagnostic
  bool new_parameters = true;  // false where only the equations' parameters may be named (plots)
  bool weights = false;        // `set weights = ...`: an unknown word may be a column meant in quotes

  Context() = default;
  Context(bool parameters_, bool signals_, bool time_, const char* what_, std::string input_, std::string known_only_ = {})
      : parameters(parameters_), signals(signals_), time(time_), what(what_), input(std::move(input_)), known_only(std::move(known_only_)) {}
};

// A parameter among the sum's own factors (not nested: those were checked where they were
// lowered) that `parameters` has no initial guess for: one linear least squares must fit.
bool has_parameter(const Sum& s, std::string* name = nullptr, const std::vector<ir::Parameter>* parameters = nullptr) {
  for (const auto& t : s.terms)
    for (const auto& [f, power] : t.factors)
      if (f.kind == FactorKind::parameter && !(parameters && (*parameters)[static_cast<std::size_t>(f.order)].guess)) {
        if (name) *name = f.name;
        return true;
      }
  return false;
}

// Any parameter anywhere in the sum, nested ones too.
bool has_nested_parameter(const Sum& s, std::string* name) {
  bool found = false;
  ir::walk_factors(s, [&](const Factor& f, const Term&) {
    if (f.kind != FactorKind::parameter) return ir::Step::into;
    *name = f.name;
    found = true;
    return ir::Step::stop;
  });
  return found;
}

// The nodes a product builds before like terms merge: every pair of terms, with both factor lists.
std::size_t product_nodes(const Sum& a, const Sum& b) {
  std::size_t factors_a = 0, factors_b = 0;
  for (const auto& t : a.terms) factors_a += t.factors.size();
  for (const auto& t : b.terms) factors_b += t.factors.size();
  return a.terms.size() * b.terms.size() + factors_a * b.terms.size() + factors_b * a.terms.size();
}

struct Lowerer {
  const ParseResult& parsed;
  Diagnostics& diagnostics;
  Declarations& decl;
  std::map<std::string, Number> constants;
  std::vector<std::pair<std::string, long long>> indices;  // sum indices in scope, innermost last
  Context context;
  bool failed = false;  // set by any error in the expression being lowered
  // Symbolic work, model-wide (ir/node_budget.hpp): nodes built by sums, products, powers and
  // derivatives; nodes of the lowered expressions written out in full.
  ir::NodeBudget built{ir::kMaxNodesBuilt};
  ir::NodeBudget written{ir::kMaxNodesWritten};
  long double sum_expansion = 1;  // how many times the enclosing sums write out what is lowered now
  bool budget_reported = false;    // the budget's error is told once, where it ran out

  Span span(const boost::spirit::x3::position_tagged& node) const { return parsed.span(node); }

  // Model::parameter_index, by a map kept up to date with the implicit parameters lowering adds:
  // a search through 10 000 parameters for every name of a large sum was quadratic.
  std::unordered_map<std::string, int> parameter_indices;
  int parameter_index(const std::string& name) {
    const auto& list = decl.model.parameters;
    for (auto k = parameter_indices.size(); k < list.size(); ++k) parameter_indices.emplace(list[k].name, static_cast<int>(k));
    const auto it = parameter_indices.find(name);
    return it == parameter_indices.end() ? -1 : it->second;
  }

  void report(Diagnostic d) {
    failed = true;
    diagnostics.add(std::move(d));
  }

  // The model-wide budget ran out here: said once, as everything lowered after fails the same way.
  void over_budget(Diagnostic d) {
    failed = true;
    if (!budget_reported) diagnostics.add(std::move(d));
    budget_reported = true;
  }

  std::vector<std::string> known_names() const {
    std::vector<std::string> names{"t", "t0", "tau", "pi"};
    for (const auto& [name, where] : decl.names) names.push_back(name);
    for (const auto& p : decl.model.parameters) names.push_back(p.name);
    for (const auto& [name, value] : indices) names.push_back(name);
    return names;
  }

  std::optional<long long> index_value(const std::string& name) const {
    for (auto it = indices.rbegin(); it != indices.rend(); ++it)
      if (it->first == name) return it->second;
    return std::nullopt;
  }

  Sum parameter(const std::string& name, const Span& where) {
    int index = parameter_index(name);
    if (index < 0 && !context.new_parameters) {
      std::vector<std::string> candidates;
      for (const auto& p : decl.model.parameters) candidates.push_back(p.name);
      report(diag::unknown_name(where, name, diag::nearest(name, candidates), true));
      return {};
    }
    if (index < 0) {  // implicit: no `param` declaration in the file
      decl.model.parameters.push_back({name, ir::Parameter::Origin::implicit, where, -1, std::nullopt, std::nullopt, false});
      index = static_cast<int>(decl.model.parameters.size()) - 1;
    }
    return ir::factor(Factor::plain(FactorKind::parameter, name, index), 1, where);
  }

  // ---- operands -------------------------------------------------------------------------------

  Sum operator()(const ast::Number& n) {
    auto value = Number::parse(n.text);
    if (!value) {
      report(diag::not_a_number(span(n), "this literal"));
      return {};
    }
    return ir::number(*value, span(n));
  }

  Sum operator()(const ast::Variable& v) {
    const std::string& name = v.name.name;
    const Span where = span(v);
    if (v.primes.size() > static_cast<std::size_t>(kMaxDerivativeOrder)) {
      report(diag::derivative_order_too_high(where, static_cast<long long>(v.primes.size()), kMaxDerivativeOrder));
      return {};
    }
    const int order = static_cast<int>(v.primes.size());
    auto constant_value = [&](const Number& value) -> Sum {
      if (order > 0) {
        report(diag::derivative_of_constant(where, name));
        return {};
      }
      return ir::number(value, where);
    };
    if (auto k = index_value(name)) return constant_value(Number(*k));
    if (auto it = constants.find(name); it != constants.end()) return constant_value(it->second);
    if (name == "pi") return constant_value(Number::real(M_PI));
    if (name == "t" || name == "tau" || name == "t0") {
      if (!context.time || (name != "t" && !context.signals)) return not_allowed(where, name);
      if (name == "t0") {  // a constant: primes on it are an error
        if (order > 0) {
          report(diag::derivative_of_constant(where, name));
          return {};
        }
        return ir::factor(Factor::plain(FactorKind::window_start), 1, where);
      }
      Sum s = ir::factor(Factor::plain(name == "t" ? FactorKind::time : FactorKind::elapsed), 1, where);
      return order == 0 ? s : differentiate(s, order).value_or(Sum{});
    }
    if (ir::Signal* s = decl.model.signal(name)) {
      if (!context.signals) return not_allowed(where, name);
      s->used = true;
      return ir::factor(Factor::plain(FactorKind::signal, name, order), 1, where);
    }
    if (decl.families.count(name)) {
      report(diag::family_needs_index(where, name));
      return {};
    }
    if (is_function_name(name)) {
      report(diag::wrong_arity(where, name, name == "der" ? "an expression and an order" : "one argument", 0));
      return {};
    }
    const bool implicit = !decl.parameters_declared && parameter_index(name) < 0;
    if (implicit && order > 0) {  // differentiated, so meant as a signal: say so
      report(diag::unknown_name(where, name, diag::nearest(name, known_names()), false));
      return {};
    }
    if (parameter_index(name) >= 0 || (!decl.parameters_declared && context.parameters)) {
      if (!context.parameters) return not_allowed(where, name);
      if (order > 0) {
        report(diag::derivative_of_parameter(where, name));
        return {};
      }
      return parameter(name, where);
    }
    if (context.weights) report(diag::weights_unknown_name(where, name, diag::nearest(name, known_names())));
    else report(diag::unknown_name(where, name, diag::nearest(name, known_names()), decl.parameters_declared));
    return {};
  }

  // A name that exists but may not be used here (a signal in a constant, ...).
  Sum not_allowed(const Span& where, const std::string& name) {
    if (!context.input.empty()) report(diag::input_definition_uses_signal(where, context.input, name));
    else if (!context.known_only.empty()) report(diag::parameter_not_allowed(where, name, context.known_only));
    else report(diag::not_a_number(where, context.what));
    return {};
  }

  Sum operator()(const ast::Signed& s) {
    Sum operand = lower(s.operand);
    return s.sign == '-' ? ir::negate(operand) : operand;
  }

  Sum operator()(const ast::Expression& e) { return lower(e); }

  Sum operator()(const ast::Indexed& x) {
    const std::string& name = x.name.name;
    const Span where = span(x);
    const bool implicit = !decl.parameters_declared && !decl.names.count(name) && !is_builtin_name(name);
    if (!decl.families.count(name) && !implicit) {
      report(diag::not_a_family(where, name, decl.model.signal(name) != nullptr));
      return {};
    }
    const auto index = integer_of(x.index);
    if (!index) return {};
    if (auto it = decl.families.find(name); it != decl.families.end()) {
      const auto [from, to] = it->second;
      if (*index < from || *index > to) {
        report(diag::index_out_of_range(where, name, *index, from, to));
        return {};
      }
    }
    if (!context.parameters) return not_allowed(where, name);
    return parameter(fmt::format("{}[{}]", name, *index), where);
  }

  std::optional<long long> integer_of(const ast::Expression& e) {
    const Context saved = context;
    context = Context{false, false, false, "an index", {}};
    const bool failed_before = failed;
    failed = false;
    Sum s = lower(e);
    const bool bad = failed;
    failed = failed_before || bad;
    context = saved;
    if (bad) return std::nullopt;
    auto n = s.as_number();
    if (!n || !n->is_integer()) {
      report(diag::index_not_integer(span(e)));
      return std::nullopt;
    }
    return n->numerator();
  }

  Sum operator()(const ast::Guard& g) {
    Factor f = Factor::plain(FactorKind::guard);
    for (const auto& c : g.conditions) {
      Sum lhs = lower(c.lhs), rhs = lower(c.rhs);
      std::string name;
      if (has_parameter(lhs, &name, &decl.model.parameters) || has_parameter(rhs, &name, &decl.model.parameters)) {
        report(diag::nonlinear_parameter(span(c), name, "it stands inside a guard `[...]`"));
        return {};
      }
      ir::Relation r = c.op == "<" ? ir::Relation::less
                     : c.op == "<=" ? ir::Relation::less_equal
                     : c.op == ">" ? ir::Relation::greater : ir::Relation::greater_equal;
      // `0 >= y'` reads as `y' <= 0`: the same region, one canonical spelling.
      if (lhs.as_number() && !rhs.as_number()) {
        std::swap(lhs, rhs);
        r = r == ir::Relation::less ? ir::Relation::greater
          : r == ir::Relation::less_equal ? ir::Relation::greater_equal
          : r == ir::Relation::greater ? ir::Relation::less : ir::Relation::less_equal;
      }
      f.conditions.push_back({ir::share(std::move(lhs)), r, ir::share(std::move(rhs))});
    }
    std::sort(f.conditions.begin(), f.conditions.end(), [](const ir::Condition& a, const ir::Condition& b) {
      Factor x = Factor::plain(FactorKind::guard), y = Factor::plain(FactorKind::guard);
      x.conditions = {a};
      y.conditions = {b};
      return ir::compare(x, y) < 0;
    });
    if (!context.signals) return not_allowed(span(g), "[...]");
    return ir::factor(std::move(f), 1, span(g));
  }

  Sum operator()(const ast::SumOver& s) {
    const std::string& name = s.index.name;
    const Span where = span(s);
    if (decl.names.count(name) || is_builtin_name(name) || index_value(name) || parameter_index(name) >= 0) {
      report(diag::index_shadows(span(s.index), name));
      return {};
    }
    if (s.from > s.to) {
      report(diag::bad_range(where, s.from, s.to));
      return {};
    }
    if (static_cast<long long>(s.to) - s.from + 1 > kMaxFamilySize) {
      report(diag::range_too_large(where, static_cast<long long>(s.to) - s.from + 1, kMaxFamilySize));
      return {};
    }
    // Refused before anything is expanded when its range times those of the sums around it is
    // more than the budget could build (each copy of the body is at least one node).
    const long double expansion = sum_expansion * static_cast<long double>(static_cast<long long>(s.to) - s.from + 1);
    if (!built.allows(expansion)) {
      over_budget(diag::sum_too_large(where, expansion, built.limit()));
      return {};
    }
    const long double outer_expansion = sum_expansion;
    sum_expansion = expansion;
    std::vector<Term> terms;
    for (long long k = s.from; k <= s.to; ++k) {
      indices.emplace_back(name, k);
      Sum body = lower(s.body);
      indices.pop_back();
      if (failed || !built.spend(1 + body.terms.size())) {
        sum_expansion = outer_expansion;
        if (built.exceeded()) over_budget(diag::sum_too_large(where, expansion, built.limit()));
        return {};
      }
      if (terms.size() + body.terms.size() > kMaxTerms) {
        sum_expansion = outer_expansion;
        report(diag::expression_too_large(where, kMaxTerms));
        return {};
      }
      terms.insert(terms.end(), body.terms.begin(), body.terms.end());
    }
    sum_expansion = outer_expansion;
    return ir::canonical(std::move(terms));
  }

  Sum operator()(const ast::Call& c) {
    const std::string& name = c.callee.name.name;
    const Span where = span(c);
    const int primes = static_cast<int>(c.callee.primes.size());
    if (ir::Signal* s = decl.model.signal(name)) return initial_value(c, *s, primes);
    if (!is_function_name(name)) {
      if (decl.names.count(name) || parameter_index(name) >= 0 || index_value(name) || is_builtin_name(name)) {
        const char* what = parameter_index(name) >= 0 ? "a parameter" : "a constant";
        report(diag::not_callable(where, name, what));
      } else {
        std::vector<std::string> candidates = function_names();
        for (const auto& sig : decl.model.signals) candidates.push_back(sig.name);
        report(diag::unknown_function(span(c.callee), name, diag::nearest(name, candidates)));
      }
      return {};
    }
    if (primes > 0) {
      report(diag::not_callable(where, name + c.callee.primes, "a derivative of a function"));
      return {};
    }
    if (name == "der") return derivative(c);
    if (c.arguments.size() != 1) {
      report(diag::wrong_arity(where, name, "one argument", c.arguments.size()));
      return {};
    }
    Sum argument = lower(c.arguments[0]);
    if (failed) return {};
    std::string parameter_name;
    if (name == "int") {
      if (!context.signals) return not_allowed(where, "int");
      return integral_of(argument);
    }
    if (has_parameter(argument, &parameter_name, &decl.model.parameters)) {
      report(diag::nonlinear_parameter(where, parameter_name, fmt::format("it stands inside `{}(...)`", name)));
      return {};
    }
    return function_of(name, std::move(argument), where);
  }

  Sum function_of(const std::string& name, Sum argument, const Span& where) {
    if (auto n = argument.as_number()) return apply_to_number(name, *n, where);
    return ir::factor(Factor{FactorKind::function, name, 0, {}, {}, ir::share(std::move(argument)), {}}, 1, where);
  }

  Sum apply_to_number(const std::string& name, const Number& n, const Span& where) {
    if (name == "abs") return ir::number(n.abs(), where);
    if (name == "sign") return ir::number(Number(n.is_zero() ? 0 : (n.is_negative() ? -1 : 1)), where);
    const double x = n.value();
    const double y = name == "sin" ? std::sin(x) : name == "cos" ? std::cos(x) : name == "exp" ? std::exp(x)
                   : name == "log" ? std::log(x) : name == "sqrt" ? std::sqrt(x) : std::tanh(x);
    if (!std::isfinite(y)) {
      report(diag::not_a_number(where, fmt::format("`{}({})`", name, n.to_string())));
      return {};
    }
    if (y == 0.0) return {};
    return ir::number(Number::real(y), where);
  }

  static bool mentions_time(const Sum& s) {
    for (const auto& term : s.terms)
      for (const auto& [f, power] : term.factors)
        if (f.kind == FactorKind::time || f.kind == FactorKind::elapsed || (f.argument && mentions_time(*f.argument))) return true;
    return false;
  }

  Sum initial_value(const ast::Call& c, ir::Signal& s, int order) {
    const Span where = span(c);
    if (c.arguments.size() != 1) {
      report(diag::bad_initial_value(where, s.name));
      return {};
    }
    Factor f = Factor::plain(FactorKind::initial_value, s.name, order);
    // `y(t0)`: at the start of the fit window; otherwise a constant time.
    const auto& arg = c.arguments[0];
    const auto* variable = arg.rest.empty() ? boost::get<ast::Variable>(&arg.first.get()) : nullptr;
    if (!(variable && variable->name.name == "t0" && variable->primes.empty())) {
      const Context saved = context;
      // Time is let through here only to recognise a delay, `u(t - 0.05)`, and say so.
      context = Context{false, false, true, "the time of an initial value", {}};
      Sum at = lower(arg);
      context = saved;
      auto n = at.as_number();
      if (failed || !n) {
        if (!failed && mentions_time(at)) report(diag::delay_not_supported(where, s.name));
        else if (!failed) report(diag::bad_initial_value(where, s.name));
        return {};
      }
      f.at = *n;
    }
    if (!context.signals) return not_allowed(where, s.name);
    s.used = true;
    return ir::factor(std::move(f), 1, where);
  }

  Sum derivative(const ast::Call& c) {
    const Span where = span(c);
    if (c.arguments.empty() || c.arguments.size() > 2) {
      report(diag::wrong_arity(where, "der", "an expression and an order", c.arguments.size()));
      return {};
    }
    int order = 1;
    if (c.arguments.size() == 2) {
      const auto n = integer_of(c.arguments[1]);
      if (!n) return {};
      if (*n < 1 || *n > 16) {
        report(diag::bad_derivative_order(span(c.arguments[1])));
        return {};
      }
      order = static_cast<int>(*n);
    }
    Sum argument = lower(c.arguments[0]);
    if (failed) return {};
    // der() is linear: parameters and other constants in time come outside.
    std::vector<Term> terms;
    for (const auto& t : argument.terms) {
      auto [constant, rest] = split_constant_part(t);
      if (rest.factors.empty()) {
        std::string name;
        if (has_parameter(ir::canonical(std::vector<Term>{constant}), &name)) {
          report(diag::derivative_of_parameter(where, name));
          return {};
        }
        continue;  // the derivative of a constant is zero
      }
      const Sum inner = ir::canonical(std::vector<Term>{rest});
      Sum d;
      if (auto symbolic = differentiate(inner, order, built)) {
        d = std::move(*symbolic);
      } else if (built.exceeded()) {
        over_budget(diag::derivative_too_large(where, built.limit()));
        return {};
      } else {
        d = ir::factor(Factor{FactorKind::derivative, "", order, {}, {}, ir::share(inner), {}}, 1, where);
      }
      if (!built.spend(d.terms.size())) {
        over_budget(diag::derivative_too_large(where, built.limit()));
        return {};
      }
      for (const auto& x : d.terms) terms.push_back(ir::multiply(constant, x));
    }
    return ir::canonical(std::move(terms));
  }

  // Each operand lowered is a node built: the budget bounds the walk of sums' bodies too.
  Sum lower(const ast::Operand& operand) {
    if (!built.spend(1)) {
      failed = true;
      return {};
    }
    return boost::apply_visitor(*this, operand);
  }

  Sum lower(const ast::Expression& e) {
    Sum result = lower(e.first);
    if (e.rest.empty()) return result;
    if (e.rest.front().op == '+' || e.rest.front().op == '-') {
      // Additive chains are gathered and made canonical once: a 10 MB line of `y+y+...` stays linear.
      std::vector<Term> terms = std::move(result.terms);
      for (const auto& step : e.rest) {
        Sum operand = lower(step.operand);  // after an error, go on: the other terms may have theirs
        if (step.op == '-') operand = ir::negate(operand);
        terms.insert(terms.end(), operand.terms.begin(), operand.terms.end());
      }
      if (failed) return {};
      return ir::canonical(std::move(terms));
    }
    for (const auto& step : e.rest) {
      Sum operand = lower(step.operand);
      if (failed) continue;  // lower the remaining factors too, for their errors
      const Span where = span(step);
      if (step.op == '*') {
        if (result.terms.size() * operand.terms.size() > kMaxTerms) {
          report(diag::expression_too_large(where, kMaxTerms));
          return {};
        }
        if (!built.spend(product_nodes(result, operand))) {
          over_budget(diag::expansion_too_large(where, built.limit()));
          return {};
        }
        result = ir::multiply(result, operand);
      } else if (step.op == '/') {
        std::string name;
        if (has_parameter(operand, &name, &decl.model.parameters)) {
          report(diag::nonlinear_parameter(where, name, "it stands in a denominator"));
          return {};
        }
        if (auto n = operand.as_number()) {
          if (n->is_zero()) {
            report(diag::division_by_zero(where));
            return {};
          }
          result = ir::scale(result, Number(1) / *n);
        } else {
          if (!built.spend(result.terms.size())) {
            over_budget(diag::expansion_too_large(where, built.limit()));
            return {};
          }
          result = ir::multiply(result, reciprocal(operand));
        }
      } else {  // '^'
        std::string name;
        if (has_parameter(operand, &name, &decl.model.parameters)) {
          report(diag::nonlinear_parameter(where, name, "it stands in an exponent"));
          return {};
        }
        if (has_nested_parameter(operand, &name)) {  // y^p with p guessed: exp(p*log(y)), its definition for real p
          result = function_of("exp", ir::multiply(operand, function_of("log", result, where)), where);
          continue;
        }
        auto exponent = operand.as_number();
        if (!exponent) {
          report(diag::exponent_not_constant(where));
          return {};
        }
        if (!std::isfinite(exponent->value())) {  // `y^2^2^2^2^2`, `y^(10^400)`
          report(diag::number_overflows(where, "the exponent"));
          return {};
        }
        if (has_parameter(result, &name, &decl.model.parameters) && !exponent->is_one()) {
          report(diag::nonlinear_parameter(where, name, fmt::format("it is raised to the power {}", exponent->to_string())));
          return {};
        }
        if (auto base = result.as_number(); base && !(base->is_zero() && exponent->is_negative())) {
          const Number power = exponent->is_integer() ? base->pow(exponent->numerator())
                                                      : Number::real(std::pow(base->value(), exponent->value()));
          if (!std::isfinite(power.value())) {
            report(diag::number_overflows(where, "this power"));
            return {};
          }
          result = ir::number(power, where);
          continue;
        }
        if (std::abs(exponent->value()) > static_cast<double>(kMaxExponent)) {
          report(diag::exponent_too_large(where, exponent->to_string(), kMaxExponent));
          return {};
        }
        if (result.empty() && exponent->is_negative()) {
          report(diag::division_by_zero(where));
          return {};
        }
        auto raised = raise(result, *exponent, kMaxTerms, &built);
        if (!raised) {
          if (built.exceeded()) over_budget(diag::expansion_too_large(where, built.limit()));
          else report(diag::expression_too_large(where, kMaxTerms));
          return {};
        }
        result = std::move(*raised);
      }
    }
    if (failed) return {};
    return result;
  }

  // Lowers one top-level expression in a context; nullopt after an error in it.
  std::optional<Sum> lower_in(const ast::Expression& e, Context c) {
    context = std::move(c);
    failed = false;
    Sum s = lower(e);
    if (failed) {
      if (built.exceeded()) over_budget(diag::expansion_too_large(span(e), built.limit()));
      return std::nullopt;
    }
    for (const auto& t : s.terms)
      if (!std::isfinite(t.coefficient.value())) {
        report(diag::not_a_number(t.span.known() ? t.span : span(e), "a coefficient (it overflows to infinity here)"));
        return std::nullopt;
      }
    if (!within_limits(s, span(e))) return std::nullopt;
    return s;
  }

  // What the runtime could not evaluate or the compiled model could not hold: more nodes written
  // out than the model may have, a derivative order past kMaxDerivativeOrder (orders of der() and
  // primes add up), a power past kMaxExponent (`(y^10000)^2`).
  bool within_limits(const Sum& s, const Span& whole) {
    // First the size, which bounds the walks below however the IR shares what it holds.
    if (!written.spend(ir::written_nodes(s, written.remaining()))) {
      over_budget(diag::model_too_many_nodes(whole, written.limit()));
      return false;
    }
    for (const auto& t : s.terms) {
      const Span where = t.span.known() ? t.span : whole;
      const int order = ir::highest_derivative_order(Sum{{t}});
      if (order > kMaxDerivativeOrder) {
        report(diag::derivative_order_too_high(where, order, kMaxDerivativeOrder));
        return false;
      }
      std::string exponent;
      ir::for_each_term(Sum{{t}}, [&](const Term& inner) {
        for (const auto& [f, power] : inner.factors) {
          if (std::abs(power) > kMaxExponent) exponent = std::to_string(power);
          if (f.kind == FactorKind::power && std::abs(f.exponent.value()) > static_cast<double>(kMaxExponent))
            exponent = f.exponent.to_string();
        }
      });
      if (!exponent.empty()) {
        report(diag::exponent_too_large(where, exponent, kMaxExponent));
        return false;
      }
    }
    return true;
  }
};

// The first signal, time or estimated quantity in `s` other than the plot's argument, with the
// span of its term, for its message. Functions, powers and guards are judged by what they hold.
std::optional<std::pair<std::string, Span>> foreign_quantity(const Sum& s, const std::string& signal, int order) {
  std::optional<std::pair<std::string, Span>> found;
  ir::walk_factors(s, [&](const Factor& f, const Term& t) {
    std::string name;
    switch (f.kind) {
      case FactorKind::parameter:
      case FactorKind::function:
      case FactorKind::power:
      case FactorKind::guard: return ir::Step::into;
      case FactorKind::signal:
        if (f.name == signal && f.order == order) return ir::Step::into;
        name = f.name + std::string(static_cast<std::size_t>(f.order), '\'');
        break;
      case FactorKind::time: name = "t"; break;
      case FactorKind::elapsed: name = "tau"; break;
      case FactorKind::window_start: name = "t0"; break;
      case FactorKind::initial_value: name = f.name + "(t0)"; break;
      case FactorKind::integral: name = "int(...)"; break;
      case FactorKind::derivative: name = "der(...)"; break;
      case FactorKind::test_function: name = "phi_j"; break;
    }
    found = std::pair{std::move(name), t.span};
    return ir::Step::stop;
  });
  return found;
}

// `plot name(y') = fitted against truth`: lowered with the equations' parameters only, split
// into sum_k a_k op_k + rest like an equation (normalize_pass), and checked to depend on its
// argument alone, so that it can be drawn over that argument's range.
std::optional<ir::PlotFunction> lower_plot(Lowerer& l, const ast::PlotStatement& p, const std::set<int>& fitted_parameters) {
  const std::string plot = p.name.name;
  const std::string argument = p.argument.name.name;
  const int order = static_cast<int>(p.argument.primes.size());
  const Span where = l.span(p);
  const ir::Signal* signal = l.decl.model.signal(argument);
  if (!signal) {
    std::vector<std::string> candidates;
    for (const auto& x : l.decl.model.signals) candidates.push_back(x.name);
    l.diagnostics.add(diag::plot_argument_not_signal(l.span(p.argument), plot, argument, diag::nearest(argument, candidates)));
    return std::nullopt;
  }
  Context fitted_context{true, true, true, "", {}};
  fitted_context.new_parameters = false;
  auto fitted = l.lower_in(p.fitted, fitted_context);
  std::optional<Sum> truth;
  if (p.truth) {
    const std::string owner = fmt::format("the truth of plot `{}`", plot);
    truth = l.lower_in(*p.truth, Context{false, true, true, "", {}, owner});
    if (!truth) return std::nullopt;
  }
  if (!fitted) return std::nullopt;
  const std::string shown = argument + std::string(static_cast<std::size_t>(order), '\'');
  for (const Sum* s : {&*fitted, truth ? &*truth : nullptr}) {
    if (!s) continue;
    if (auto other = foreign_quantity(*s, argument, order)) {
      l.diagnostics.add(diag::plot_uses_other_quantity(other->second.known() ? other->second : where, plot, other->first, shown));
      return std::nullopt;
    }
  }
  ir::PlotFunction out;
  out.name = plot;
  out.span = where;
  out.signal = argument;
  out.order = order;
  out.truth = std::move(truth);
  // A parameter inside a function of the plot has a value only when the equations made it
  // nonlinear (and the fit holds it at one).
  std::string unfitted;
  ir::walk_factors(*fitted, [&](const Factor& f, const Term&) {
    ir::for_each_nested_sum(f, [&](const Sum& inner) {
      ir::for_each_factor(inner, [&](const Factor& g) {
        if (g.kind == FactorKind::parameter && !l.decl.model.parameters[static_cast<std::size_t>(g.order)].nonlinear && unfitted.empty())
          unfitted = g.name;
      });
    });
    return ir::Step::over;
  });
  if (!unfitted.empty()) {
    l.diagnostics.add(diag::plot_parameter_not_fitted(where, plot, unfitted));
    return std::nullopt;
  }
  auto split = split_by_parameter(*fitted, l.decl.model, l.diagnostics);
  if (!split) return std::nullopt;
  for (auto& [parameter, terms] : split->operations) {
    // Only what the fit estimates can be drawn: a declared parameter no equation uses has no value.
    if (!fitted_parameters.count(parameter)) {
      const auto& name = l.decl.model.parameters[static_cast<std::size_t>(parameter)].name;
      l.diagnostics.add(diag::plot_parameter_not_fitted(terms.front().span.known() ? terms.front().span : where, plot, name));
      return std::nullopt;
    }
    out.terms.push_back({parameter, ir::canonical(std::move(terms))});
  }
  std::erase_if(out.terms, [](const ir::ParameterTerm& x) { return x.operation.empty(); });
  out.rest = ir::canonical(std::move(split->rest));
  if (out.terms.empty()) {
    l.diagnostics.add(diag::plot_without_parameter(where, plot));
    return std::nullopt;
  }
  return out;
}

// Marks the parameters with a guess that stand anywhere but as the one plain factor of a term:
// inside a function, power or denominator, to a power, or beside another parameter. Only those
// stay in the operations (Parameter::nonlinear); a guessed parameter that enters linearly
// everywhere is fitted linearly, its guess unused.
void mark_nonlinear(const Sum& s, std::vector<ir::Parameter>& parameters) {
  const auto mark_nested = [&](const Sum& inner) {
    ir::for_each_factor(inner, [&](const Factor& g) {
      if (g.kind == FactorKind::parameter) parameters[static_cast<std::size_t>(g.order)].nonlinear = true;
    });
  };
  for (const auto& t : s.terms) {
    const auto count = std::count_if(t.factors.begin(), t.factors.end(), [](const auto& f) { return f.first.kind == FactorKind::parameter; });
    for (const auto& [f, power] : t.factors) {
      if (f.kind != FactorKind::parameter) {
        ir::for_each_nested_sum(f, mark_nested);
        continue;
      }
      ir::Parameter& p = parameters[static_cast<std::size_t>(f.order)];
      if (p.guess && (power != 1 || count > 1)) p.nonlinear = true;
    }
  }
}

}  // namespace

LoweredModel lower_pass(Declarations declarations, const ParseResult& parsed, Diagnostics& diagnostics) {
  Lowerer l{parsed, diagnostics, declarations, {}, {}, {}, false, ir::NodeBudget{ir::kMaxNodesBuilt}, ir::NodeBudget{ir::kMaxNodesWritten}, 1, false, {}};
  for (const auto& c : declarations.constants) {
    auto value = l.lower_in(*c.value, Context{false, false, false, "a constant", {}});
    if (!value) continue;
    if (auto n = value->as_number()) l.constants.emplace(c.name, *n);
    else diagnostics.add(diag::not_a_number(l.span(*c.value), fmt::format("constant `{}`", c.name)));
  }
  for (const auto& g : declarations.guesses) {
    auto value = l.lower_in(*g.value, Context{false, false, false, "a parameter's initial guess", {}});
    if (!value) continue;
    const auto n = value->as_number();
    if (!n || !std::isfinite(n->value())) {
      diagnostics.add(diag::not_a_number(l.span(*g.value), "a parameter's initial guess"));
      continue;
    }
    for (std::size_t k = 0; k < g.count; ++k) declarations.model.parameters[g.first + k].guess = *n;
  }
  for (const auto& d : declarations.input_definitions) {
    auto& signal = declarations.model.signals[d.signal];
    if (auto value = l.lower_in(*d.definition, Context{false, false, true, "an input definition", signal.name}))
      signal.definition = std::move(*value);
  }
  LoweredModel out;
  for (const auto& pending : declarations.equations) {
    const ast::Equation& e = *pending.equation;
    auto lhs = l.lower_in(e.lhs, Context{true, true, true, "", {}});
    auto rhs = l.lower_in(e.rhs, Context{true, true, true, "", {}});
    if (lhs && rhs) out.equations.push_back({parsed.span(e), std::move(*lhs), std::move(*rhs), pending.integration});
  }
  for (const auto& e : out.equations)
    for (const Sum* side : {&e.lhs, &e.rhs}) mark_nonlinear(*side, declarations.model.parameters);
  if (declarations.equations.empty() && !diagnostics.has_errors())
    diagnostics.add(diag::empty_model(Span{parsed.source, 0, 0}));
  for (const auto& s : declarations.model.signals) {
    if (s.used) continue;
    if (diagnostics.has_errors()) break;  // an earlier error may be why it looks unused
    diagnostics.add(s.kind == ir::Signal::Kind::output ? diag::output_unused(s.span, s.name) : diag::input_unused(s.span, s.name));
  }
  // After the unused-signal check: a signal that only weights or a plot name is still unused.
  if (declarations.weights) {
    Context weights{false, true, true, "the weights", {}, "the weights"};
    weights.weights = true;
    if (auto value = l.lower_in(*declarations.weights, weights))
      declarations.model.weights = ir::WeightExpression{std::move(*value), declarations.weights_span};
  }
  std::set<int> fitted_parameters;  // the parameters some equation uses
  for (const auto& e : out.equations)
    for (const Sum* side : {&e.lhs, &e.rhs})
      for (const auto& t : side->terms)
        for (const auto& [f, power] : t.factors)
          if (f.kind == FactorKind::parameter) fitted_parameters.insert(f.order);
  for (const ast::PlotStatement* p : declarations.plots)
    if (auto plot = lower_plot(l, *p, fitted_parameters)) declarations.model.plots.push_back(std::move(*plot));
  out.model = std::move(declarations.model);
  out.model.constants = std::move(l.constants);
  return out;
}

}  // namespace sidc
