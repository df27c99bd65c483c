#include "ir/print.hpp"

#include <fmt/format.h>

namespace sidc {
namespace {

using ir::FactorKind;

// A sum that needs no parentheses as the base of `^` or as a factor: one factor, coefficient 1.
bool is_atom(const ir::Sum& s) {
  return s.terms.size() == 1 && s.terms[0].coefficient.is_one() && s.terms[0].factors.size() == 1 &&
         s.terms[0].factors[0].second == 1;
}

// An exponent as the grammar reads it back after `^`: decimals and integers as they are,
// other rationals in parentheses (`y^1/3` would mean (y^1)/3).
std::string exponent_text(const Number& e) {
  const std::string s = e.to_string();
  return s.find('/') == std::string::npos ? s : "(" + s + ")";
}

std::string with_power(const std::string& base, int power) {
  return power == 1 ? base : fmt::format("{}^{}", base, power);
}

// A factor about to be raised to `power`: `(y^1.5)^2`, since `y^1.5^2` would read as y^(1.5^2).
std::string base_text(const ir::Factor& f, int power) {
  return f.kind == FactorKind::power && power != 1 ? "(" + print(f) + ")" : print(f);
}

// |coefficient| * factors, the sign printed by the caller.
std::string magnitude(const ir::Term& t) {
  std::string numerator, denominator;
  const Number c = t.coefficient.abs();
  const std::string c_text = c.to_string();
  const auto slash = c_text.find('/');
  for (const auto& [f, power] : t.factors) {
    if (power > 0) {
      numerator += (numerator.empty() ? "" : "*") + with_power(base_text(f, power), power);
    } else {
      denominator += "/" + with_power(base_text(f, -power), -power);
    }
  }
  std::string out;
  if (slash != std::string::npos) {  // exact rational: numerator*factors/denominator
    const std::string top = c_text.substr(0, slash);
    out = top == "1" && !numerator.empty() ? numerator : (numerator.empty() ? top : top + "*" + numerator);
    out += "/" + c_text.substr(slash + 1) + denominator;
  } else {
    if (numerator.empty()) out = c_text;
    else out = c.is_one() ? numerator : c_text + "*" + numerator;
    out += denominator;
  }
  return out;
}

// Breaks a long equation after top-level ` + `, ` - ` or ` = ` (the grammar continues a statement
// after a trailing operator), filling lines up to `width` characters; continuation lines indented.
std::string wrap(const std::string& text, std::size_t width = 100, std::size_t indent_width = 4) {
  if (text.size() <= width) return text;
  std::vector<std::size_t> breaks;  // positions just after "+ ", "- " or "= " at depth 0
  int depth = 0;
  for (std::size_t i = 0; i + 2 < text.size(); ++i) {
    const char c = text[i];
    if (c == '(' || c == '[') ++depth;
    if (c == ')' || c == ']') --depth;
    if (depth == 0 && i > 0 && text[i - 1] == ' ' && (c == '+' || c == '-' || c == '=') && text[i + 1] == ' ') breaks.push_back(i + 1);
  }
  std::string out;
  std::size_t line_start = 0, last_fit = 0;
  const std::string indent(indent_width, ' ');
  for (std::size_t b : breaks) {
    const std::size_t limit = width - (line_start == 0 ? 0 : indent.size());
    if (b - line_start > limit && last_fit > line_start) {
      out += (line_start ? indent : "") + text.substr(line_start, last_fit - line_start) + "\n";
      line_start = last_fit + 1;  // skip the space after the operator
    }
    last_fit = b;
  }
  out += (line_start ? indent : "") + text.substr(line_start);
  return out;
}

}  // namespace

std::string print(const ir::Factor& f) {
  switch (f.kind) {
    case FactorKind::parameter: return f.name;
    case FactorKind::signal: return f.name + std::string(static_cast<std::size_t>(f.order), '\'');
    case FactorKind::time: return "t";
    case FactorKind::elapsed: return "tau";
    case FactorKind::window_start: return "t0";
    case FactorKind::initial_value:
      return fmt::format("{}{}({})", f.name, std::string(static_cast<std::size_t>(f.order), '\''),
                         f.at ? f.at->to_string() : std::string("t0"));
    case FactorKind::function: return fmt::format("{}({})", f.name, print(*f.argument));
    case FactorKind::power: {
      const std::string base = is_atom(*f.argument) ? print(*f.argument) : "(" + print(*f.argument) + ")";
      return fmt::format("{}^{}", base, exponent_text(f.exponent));
    }
    case FactorKind::derivative: return fmt::format("der({}, {})", print(*f.argument), f.order);
    case FactorKind::integral: return fmt::format("int({})", print(*f.argument));
    case FactorKind::test_function: return "phi_j" + std::string(static_cast<std::size_t>(f.order), '\'');
    case FactorKind::guard: {
      std::string out = "[";
      for (std::size_t i = 0; i < f.conditions.size(); ++i) {
        const auto& c = f.conditions[i];
        out += fmt::format("{}{} {} {}", i ? " and " : "", print(*c.lhs), ir::to_string(c.relation), print(*c.rhs));
      }
      return out + "]";
    }
  }
  return "?";
}

std::string print(const ir::Term& t) { return (t.coefficient.is_negative() ? "-" : "") + magnitude(t); }

std::string print(const ir::Sum& s) {
  if (s.terms.empty()) return "0";
  std::string out;
  for (std::size_t i = 0; i < s.terms.size(); ++i) {
    const auto& t = s.terms[i];
    if (i == 0) out += print(t);
    else out += (t.coefficient.is_negative() ? " - " : " + ") + magnitude(t);
  }
  return out;
}

namespace {

// sum_k a_k * op_k, each parameter folded into its operation where that reads naturally.
std::string print_parameter_terms(const std::vector<ir::ParameterTerm>& terms, const ir::Model& m) {
  std::string lhs;
  for (const auto& [index, operation] : terms) {
    const auto& name = m.parameters[static_cast<std::size_t>(index)].name;
    ir::Factor p{ir::FactorKind::parameter, name, index, {}, {}, {}, {}};
    std::string text;
    bool negative = false;
    if (operation.terms.size() == 1) {  // a_k folded into the one term: `a2*y^3/3`
      const ir::Term with_parameter = ir::multiply(operation.terms[0], ir::Term{Number(1), {{p, 1}}, {}});
      negative = with_parameter.coefficient.is_negative();
      text = magnitude(with_parameter);
    } else {
      text = name + "*(" + print(operation) + ")";
    }
    if (lhs.empty()) lhs = negative ? "-" + text : text;
    else lhs += (negative ? " - " : " + ") + text;
  }
  return lhs;
}

}  // namespace

std::string print(const ir::Equation& e, const ir::Model& m) { return print_parameter_terms(e.terms, m) + " = " + print(e.known); }

std::string print(const ir::PlotFunction& p, const ir::Model& m) {
  std::string out = fmt::format("plot {}({}{}) = {}", p.name, p.signal, std::string(static_cast<std::size_t>(p.order), '\''),
                                print_parameter_terms(p.terms, m));
  if (!p.rest.empty()) out += " + (" + print(p.rest) + ")";
  if (p.truth) out += " against " + print(*p.truth);
  return out;
}

std::string print_wrapped(const ir::Equation& e, const ir::Model& m, std::size_t width, std::size_t indent) {
  return wrap(print(e, m), width, indent);
}

std::string print(const ir::Model& m) {
  std::string out;
  if (!m.name.empty()) out += "model " + m.name + "\n";
  auto declare = [&](const char* keyword, ir::Signal::Kind kind) {
    std::string names;
    for (const auto& s : m.signals) {
      if (s.kind != kind) continue;
      names += (names.empty() ? "" : ", ") + s.name + (s.unit ? " [" + to_string(*s.unit) + "]" : "") +
               (s.hold != ir::Signal::Hold::smooth ? std::string(" ") + to_string(s.hold) : "") +
               (s.definition ? " = " + print(*s.definition) : "");
    }
    if (!names.empty()) out += fmt::format("{} {}\n", keyword, names);
  };
  declare("input", ir::Signal::Kind::input);
  declare("output", ir::Signal::Kind::output);
  // Parameters, with runs of a family written back as a range: c[1], c[2], c[3] -> c[1..3].
  std::string params;
  for (std::size_t i = 0; i < m.parameters.size();) {
    const std::string& name = m.parameters[i].name;
    std::string item = name;
    const auto bracket = name.find('[');
    if (bracket != std::string::npos) {
      const std::string family = name.substr(0, bracket);
      const int first = std::stoi(name.substr(bracket + 1));
      std::size_t j = i + 1;
      const auto& guess = m.parameters[i].guess;
      while (j < m.parameters.size() && m.parameters[j].name == fmt::format("{}[{}]", family, first + static_cast<int>(j - i)) &&
             m.parameters[j].guess.has_value() == guess.has_value() && (!guess || *m.parameters[j].guess == *guess))
        ++j;
      item = j - i > 1 ? fmt::format("{}[{}..{}]", family, first, first + static_cast<int>(j - i) - 1) : name;
      if (guess) item += " = " + guess->to_string();
      i = j;
    } else {
      if (m.parameters[i].guess) item += " = " + m.parameters[i].guess->to_string();
      ++i;
    }
    params += (params.empty() ? "" : ", ") + item;
  }
  if (!params.empty()) out += "param " + params + "\n";
  for (const auto& d : m.data) {
    std::string bindings;
    for (const auto& [signal, column] : d.bindings) bindings += fmt::format("{}{} = \"{}\"", bindings.empty() ? "" : ", ", signal, column);
    for (const auto& x : d.exact_derivatives)
      bindings += fmt::format("{}{}{} = \"{}\"", bindings.empty() ? "" : ", ", x.signal, std::string(static_cast<std::size_t>(x.order), '\''), x.column);
    out += fmt::format("data \"{}\"{}\n", d.path, bindings.empty() ? "" : " (" + bindings + ")");
  }
  for (const auto& [key, value] : m.settings.values) out += fmt::format("set {} = {}\n", key, value.text);
  if (m.weights) out += "set weights = " + print(m.weights->value) + "\n";
  // `integrate` and `constants` apply to the equations after them: print them where they change.
  ir::IntegrationRequest current;
  for (const auto& e : m.equations) {
    const auto& r = e.integration;
    if (r.weak && !current.weak) out += "set form = weak\n";
    if (e.weak) out += "# weak form: the equation below holds integrated against every test function phi_j over its subdomain\n";
    if (!r.weak && (r.count != current.count || r.times != current.times || current.weak))
      out += fmt::format("set integrate = {}\n", r.count == ir::IntegrationRequest::Count::automatic ? "auto" : std::to_string(r.times));
    if (r.constants != current.constants)
      out += fmt::format("set constants = {}\n", r.constants == ir::IntegrationRequest::Constants::initial ? "initial" : "fitted");
    current = r;
    out += wrap(print(e, m)) + "\n";
  }
  for (const auto& p : m.plots) out += wrap(print(p, m)) + "\n";
  return out;
}

}  // namespace sidc
