#include "compiler/declare_pass.hpp"

#include <algorithm>
#include <optional>
#include <fmt/format.h>

#include "ir/settings.hpp"
#include "diagnostics/model_catalogue.hpp"

namespace sidc {

const std::vector<std::string>& function_names() {
  static const std::vector<std::string> names{"sin", "cos", "exp", "log", "sqrt", "abs", "sign", "tanh", "der", "int"};
  return names;
}

bool is_function_name(const std::string& name) {
  const auto& f = function_names();
  return std::find(f.begin(), f.end(), name) != f.end();
}

bool is_builtin_name(const std::string& name) {
  return name == "t" || name == "t0" || name == "tau" || name == "pi" || name == "sum" || is_function_name(name);
}

namespace {

struct Declarer {
  const ParseResult& parsed;
  Diagnostics& diagnostics;
  Declarations out;
  ir::IntegrationRequest current_integration;
  std::map<std::string, Span> set_once;  // global settings already seen
  // The last `set form|integrate|constants` no equation has followed yet: it applies to the
  // equations after it, so one after the last equation applies to nothing (a warning).
  std::optional<std::pair<std::string, Span>> pending_equation_setting;

  Span span(const boost::spirit::x3::position_tagged& node) const { return parsed.span(node); }

  // Records a new name; false (and a diagnostic) when it is built-in or taken.
  bool declare(const std::string& name, const Span& where) {
    if (is_builtin_name(name)) {
      diagnostics.add(diag::reserved_name(where, name));
      return false;
    }
    if (auto it = out.names.find(name); it != out.names.end()) {
      diagnostics.add(diag::declared_twice(where, name, it->second));
      return false;
    }
    out.names.emplace(name, where);
    return true;
  }

  void operator()(const ast::ModelName& m) {
    if (!out.model.name.empty()) diagnostics.add(diag::setting_repeated(span(m), "model", out.model.name_span));
    out.model.name = m.name.name;
    out.model.name_span = span(m);
  }

  void operator()(const ast::SignalDeclaration& d) {
    for (const auto& item : d.signals) {
      const Span where = span(item.name);
      if (!declare(item.name.name, where)) continue;
      ir::Signal s;
      s.name = item.name.name;
      s.kind = d.kind == "input" ? ir::Signal::Kind::input : ir::Signal::Kind::output;
      s.span = where;
      if (item.unit) {
        ir::UnitParseError error;
        s.unit = ir::parse_unit(item.unit->text, &error);
        if (!s.unit) {
          const std::size_t at = item.unit->offset + error.offset;
          diagnostics.add(diag::bad_unit(Span{where.file, at, at + 1}, s.name, error.message));
          continue;
        }
      }
      if (item.hold) {
        const Span hold_at = span(*item.hold);
        const auto hold = ir::hold_from(item.hold->name);
        if (!hold) {
          diagnostics.add(diag::unknown_hold(hold_at, s.name, item.hold->name));
          continue;
        }
        if (s.kind == ir::Signal::Kind::output) {
          diagnostics.add(diag::hold_on_output(hold_at, s.name, item.hold->name));
          continue;
        }
        if (item.definition) {
          diagnostics.add(diag::hold_on_defined_input(hold_at, s.name, item.hold->name));
          continue;
        }
        s.hold = *hold;
        s.hold_span = hold_at;
      }
      if (item.definition) {
        if (s.kind == ir::Signal::Kind::output) {
          diagnostics.add(diag::bad_setting_value(where, "output", s.name + " = ...", "only names; an input may be given as an expression of t"));
          continue;
        }
        out.input_definitions.push_back({out.model.signals.size(), &*item.definition});
      }
      out.model.signals.push_back(std::move(s));
    }
  }

  void operator()(const ast::ParameterDeclaration& d) {
    out.parameters_declared = true;
    for (const auto& item : d.parameters) {
      const Span where = span(item);
      if (!declare(item.name.name, where)) continue;
      if (item.from && item.to) {
        const int from = *item.from, to = *item.to;
        if (from > to) {
          diagnostics.add(diag::bad_range(where, from, to));
          continue;
        }
        if (static_cast<long long>(to) - from + 1 > kMaxFamilySize) {
          diagnostics.add(diag::range_too_large(where, static_cast<long long>(to) - from + 1, kMaxFamilySize));
          continue;
        }
        out.families[item.name.name] = {from, to};
        if (item.guess) out.guesses.push_back({out.model.parameters.size(), static_cast<std::size_t>(to - from + 1), &*item.guess});
        for (int k = from; k <= to; ++k)
          out.model.parameters.push_back({fmt::format("{}[{}]", item.name.name, k), ir::Parameter::Origin::declared, where, -1, std::nullopt, std::nullopt, false});
      } else {
        if (item.guess) out.guesses.push_back({out.model.parameters.size(), 1, &*item.guess});
        out.model.parameters.push_back({item.name.name, ir::Parameter::Origin::declared, where, -1, std::nullopt, std::nullopt, false});
      }
    }
  }

  void operator()(const ast::ConstantDeclaration& d) {
    for (const auto& item : d.constants) {
      const Span where = span(item.name);
      if (declare(item.name.name, where)) out.constants.push_back({item.name.name, &item.value, where});
    }
  }

  void operator()(const ast::DataStatement& d) {
    ir::DataSource source;
    source.path = d.path;
    source.span = span(d);
    for (const auto& b : d.bindings) {
      const Span where = span(b);
      const std::string& name = b.signal.name.name;
      if (!b.signal.primes.empty()) {  // an exact derivative, recorded for comparison
        const int order = static_cast<int>(b.signal.primes.size());
        const auto already = std::find_if(source.exact_derivatives.begin(), source.exact_derivatives.end(),
                                          [&](const auto& x) { return x.signal == name && x.order == order; });
        if (already != source.exact_derivatives.end()) diagnostics.add(diag::binding_repeated(where, name + b.signal.primes));
        else source.exact_derivatives.push_back({name, order, b.column, where});
        continue;
      }
      const auto already = std::find_if(source.bindings.begin(), source.bindings.end(),
                                        [&](const auto& x) { return x.first == name; });
      if (already != source.bindings.end()) {
        diagnostics.add(diag::binding_repeated(where, name));
        continue;
      }
      source.bindings.emplace_back(name, b.column);
      source.binding_spans.push_back(where);
    }
    out.model.data.push_back(std::move(source));
  }

  void operator()(const ast::Setting& s) {
    const std::string& key = s.key.name;
    const Span key_span = span(s.key);
    const Span value_span{parsed.source, s.value_offset, s.value_offset + s.value.size()};
    const auto problem = check_setting(key, s.value);
    if (problem.unknown_key) {
      diagnostics.add(diag::unknown_setting(key_span, key, diag::nearest(key, setting_keys())));
      return;
    }
    if (!problem.expected.empty()) {
      diagnostics.add(diag::bad_setting_value(value_span, key, s.value, problem.expected));
      return;
    }
    if (key == "form" || key == "integrate" || key == "constants") pending_equation_setting.emplace(key, key_span);
    if (key == "form") {  // the same request as `integrate`, named by its form
      current_integration.span = value_span;
      request_form(current_integration, s.value);
      return;
    }
    if (key == "integrate") {
      current_integration.span = value_span;
      current_integration.weak = false;
      if (s.value == "auto") {
        current_integration.count = ir::IntegrationRequest::Count::automatic;
      } else {
        current_integration.count = ir::IntegrationRequest::Count::fixed;
        current_integration.times = std::stoi(s.value);
      }
      return;
    }
    if (key == "constants") {
      current_integration.constants =
          s.value == "initial" ? ir::IntegrationRequest::Constants::initial : ir::IntegrationRequest::Constants::fitted;
      return;
    }
    if (auto it = set_once.find(key); it != set_once.end()) {
      diagnostics.add(diag::setting_repeated(key_span, key, it->second));
      return;
    }
    set_once.emplace(key, key_span);
    out.model.settings.values[key] = {s.value, value_span};
  }

  // The column form is an ordinary setting (its text quoted, as `set weights = "w"` reads); the
  // expression form is lowered with the equations (lower_pass.cpp).
  void operator()(const ast::WeightsSetting& s) {
    const Span where = span(s);
    if (auto it = set_once.find("weights"); it != set_once.end()) {
      diagnostics.add(diag::setting_repeated(where, "weights", it->second));
      return;
    }
    set_once.emplace("weights", where);
    if (const auto* column = boost::get<std::string>(&s.value.get())) {
      out.model.settings.values["weights"] = {"\"" + *column + "\"", where};
    } else {
      out.weights = &boost::get<ast::Expression>(s.value.get());
      out.weights_span = where;
    }
  }

  void operator()(const ast::PlotStatement& p) {
    if (declare(p.name.name, span(p.name))) out.plots.push_back(&p);
  }

  void operator()(const ast::Equation& e) {
    out.equations.push_back({&e, current_integration});
    pending_equation_setting.reset();
  }
};

}  // namespace

Declarations declare_pass(const ParseResult& parsed, Diagnostics& diagnostics) {
  Declarer d{parsed, diagnostics, {}, {}, {}, {}};
  for (const auto& statement : parsed.model.statements) boost::apply_visitor(d, statement);
  if (d.pending_equation_setting && !d.out.equations.empty())
    diagnostics.add(diag::setting_after_last_equation(d.pending_equation_setting->second, d.pending_equation_setting->first));

  // Bindings name declared signals (or `t`), and not inputs given as expressions.
  auto signal_names = [&] {
    std::vector<std::string> names{"t"};
    for (const auto& x : d.out.model.signals) names.push_back(x.name);
    return names;
  };
  for (auto& source : d.out.model.data)
    for (const auto& exact : source.exact_derivatives)
      if (!d.out.model.signal(exact.signal))
        diagnostics.add(diag::binding_unknown_signal(exact.span, exact.signal, diag::nearest(exact.signal, signal_names())));
  for (auto& source : d.out.model.data) {
    for (std::size_t i = 0; i < source.bindings.size(); ++i) {
      const auto& name = source.bindings[i].first;
      const Span& where = source.binding_spans[i];
      if (name == "t") continue;
      const ir::Signal* s = d.out.model.signal(name);
      if (!s) {
        std::vector<std::string> candidates{"t"};
        for (const auto& x : d.out.model.signals) candidates.push_back(x.name);
        diagnostics.add(diag::binding_unknown_signal(where, name, diag::nearest(name, candidates)));
      } else if (std::any_of(d.out.input_definitions.begin(), d.out.input_definitions.end(),
                             [&](const auto& def) { return d.out.model.signals[def.signal].name == name; })) {
        diagnostics.add(diag::binding_of_defined_input(where, name));
      }
    }
  }
  // An empty fit window is the model's mistake, told at its `set` (command-line overrides are
  // checked with the other options).
  const auto& settings = d.out.model.settings.values;
  if (auto from = settings.find("from"), to = settings.find("to"); from != settings.end() && to != settings.end()) {
    const double a = Number::parse(from->second.text)->value(), b = Number::parse(to->second.text)->value();
    if (a > b) {  // as FitOptions::is_valid: equal ends are judged with the record
      const bool to_later = to->second.span.begin > from->second.span.begin;
      const auto& later = to_later ? to->second : from->second;
      const auto& earlier = to_later ? from->second : to->second;
      diagnostics.add(diag::empty_fit_window_setting(later.span, from->second.text, to->second.text, earlier.span));
    }
  }
  return std::move(d.out);
}

}  // namespace sidc
