// A compact, fully bracketed text of an AST, so that tests can state the expected tree in one
// line. Every Expression is printed in parentheses with its operators, so precedence and
// associativity are visible: `a + b*c` is `(a + (b * c))`, `y^2^3` is `(y ^ (2 ^ 3))`,
// `-y^2` is `-(y ^ 2)`. Calls print as `f(...)`, family members as `c[...]`, guards as
// `[... and ...]`, sums as `sum(k = 1..6, ...)`.
#pragma once

#include <string>

#include "grammar/ast.hpp"

namespace sidc::ast_text {

std::string text(const ast::Expression& e);

inline std::string text(const ast::Operand& operand) {
  struct Visitor {
    using result_type = std::string;
    std::string operator()(const ast::Number& n) const { return n.text; }
    std::string operator()(const ast::Variable& v) const { return v.name.name + v.primes; }
    std::string operator()(const ast::Signed& s) const { return std::string(1, s.sign) + text(s.operand); }
    std::string operator()(const ast::Call& c) const {
      std::string out = c.callee.name.name + c.callee.primes + "(";
      for (std::size_t i = 0; i < c.arguments.size(); ++i) out += (i ? ", " : "") + text(c.arguments[i]);
      return out + ")";
    }
    std::string operator()(const ast::Indexed& x) const { return x.name.name + "[" + text(x.index) + "]"; }
    std::string operator()(const ast::Guard& g) const {
      std::string out = "[";
      for (std::size_t i = 0; i < g.conditions.size(); ++i)
        out += (i ? " and " : "") + text(g.conditions[i].lhs) + " " + g.conditions[i].op + " " + text(g.conditions[i].rhs);
      return out + "]";
    }
    std::string operator()(const ast::SumOver& s) const {
      return "sum(" + s.index.name + " = " + std::to_string(s.from) + ".." + std::to_string(s.to) + ", " + text(s.body) + ")";
    }
    std::string operator()(const ast::Expression& e) const { return text(e); }
  };
  return boost::apply_visitor(Visitor{}, operand.get());
}

inline std::string text(const ast::Expression& e) {
  if (e.rest.empty()) return text(e.first);
  std::string out = "(";
  out += text(e.first);
  for (const auto& operation : e.rest) out += std::string(" ") + operation.op + " " + text(operation.operand);
  return out + ")";
}

inline std::string text(const ast::Statement& statement) {
  struct Visitor {
    using result_type = std::string;
    std::string operator()(const ast::ModelName& m) const { return "model " + m.name.name; }
    std::string operator()(const ast::SignalDeclaration& d) const {
      std::string out = d.kind;
      for (std::size_t i = 0; i < d.signals.size(); ++i) {
        out += (i ? ", " : " ") + d.signals[i].name.name;
        if (d.signals[i].definition) out += " = " + text(*d.signals[i].definition);
      }
      return out;
    }
    std::string operator()(const ast::ParameterDeclaration& d) const {
      std::string out = "param";
      for (std::size_t i = 0; i < d.parameters.size(); ++i) {
        out += (i ? ", " : " ") + d.parameters[i].name.name;
        if (d.parameters[i].from) {
          out += '[';
          out += std::to_string(*d.parameters[i].from);
          out += "..";
          out += std::to_string(d.parameters[i].to.value_or(-999));
          out += ']';
        }
      }
      return out;
    }
    std::string operator()(const ast::ConstantDeclaration& d) const {
      std::string out = "const";
      for (std::size_t i = 0; i < d.constants.size(); ++i)
        out += (i ? ", " : " ") + d.constants[i].name.name + " = " + text(d.constants[i].value);
      return out;
    }
    std::string operator()(const ast::DataStatement& d) const {
      std::string out = "data <" + d.path + ">";
      for (std::size_t i = 0; i < d.bindings.size(); ++i)
        out += (i ? ", " : " (") + d.bindings[i].signal.name.name + d.bindings[i].signal.primes + " = <" +
               d.bindings[i].column + ">";
      return d.bindings.empty() ? out : out + ")";
    }
    std::string operator()(const ast::Setting& s) const {
      return "set " + s.key.name + " = <" + s.value + ">@" + std::to_string(s.value_offset);
    }
    std::string operator()(const ast::WeightsSetting& s) const {
      if (const auto* column = boost::get<std::string>(&s.value.get())) return "set weights = column <" + *column + ">";
      return "set weights = " + text(boost::get<ast::Expression>(s.value.get()));
    }
    std::string operator()(const ast::PlotStatement& p) const {
      return "plot " + p.name.name + "(" + p.argument.name.name + p.argument.primes + ") = " + text(p.fitted) +
             (p.truth ? " against " + text(*p.truth) : std::string());
    }
    std::string operator()(const ast::Equation& e) const { return text(e.lhs) + " = " + text(e.rhs); }
  };
  return boost::apply_visitor(Visitor{}, statement.get());
}

}  // namespace sidc::ast_text
