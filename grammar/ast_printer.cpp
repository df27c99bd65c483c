#include "grammar/ast_printer.hpp"

#include <fmt/format.h>

namespace sidc {
namespace {

struct AstPrinter {
  std::string out;

  void operator()(const ast::Number& n) { out += n.text; }
  void operator()(const ast::Variable& v) { out += v.name.name + v.primes; }
  void operator()(const ast::Signed& s) {
    out += fmt::format("({} ", s.sign);
    boost::apply_visitor(*this, s.operand);
    out += ")";
  }
  void operator()(const ast::Expression& e) {
    if (e.rest.empty()) {
      boost::apply_visitor(*this, e.first);
      return;
    }
    // Left-nested, as the operations fold: (+ (+ a b) c).
    for (std::size_t i = e.rest.size(); i-- > 0;) out += fmt::format("({} ", e.rest[i].op);
    boost::apply_visitor(*this, e.first);
    for (const auto& step : e.rest) {
      out += " ";
      boost::apply_visitor(*this, step.operand);
      out += ")";
    }
  }
  void operator()(const ast::Call& c) {
    out += fmt::format("(call {}{}", c.callee.name.name, c.callee.primes);
    for (const auto& a : c.arguments) {
      out += " ";
      (*this)(a);
    }
    out += ")";
  }
  void operator()(const ast::Indexed& x) {
    out += fmt::format("(index {} ", x.name.name);
    (*this)(x.index);
    out += ")";
  }
  void operator()(const ast::Guard& g) {
    out += "(guard";
    for (const auto& c : g.conditions) {
      out += fmt::format(" ({} ", c.op);
      (*this)(c.lhs);
      out += " ";
      (*this)(c.rhs);
      out += ")";
    }
    out += ")";
  }
  void operator()(const ast::SumOver& s) {
    out += fmt::format("(sum {} {} {} ", s.index.name, s.from, s.to);
    (*this)(s.body);
    out += ")";
  }

  // statements
  void operator()(const ast::ModelName& m) { out += fmt::format("(model {})\n", m.name.name); }
  void operator()(const ast::SignalDeclaration& d) {
    out += "(" + d.kind;
    for (const auto& s : d.signals) {
      out += " " + s.name.name;
      if (s.unit) out += " [" + s.unit->text + "]";
      if (s.hold) out += " " + s.hold->name;
      if (s.definition) {
        out += " = ";
        (*this)(*s.definition);
      }
    }
    out += ")\n";
  }
  void operator()(const ast::ParameterDeclaration& d) {
    out += "(param";
    for (const auto& p : d.parameters) {
      out += p.from ? fmt::format(" {}[{}..{}]", p.name.name, *p.from, *p.to) : " " + p.name.name;
      if (p.guess) {
        out += " = ";
        (*this)(*p.guess);
      }
    }
    out += ")\n";
  }
  void operator()(const ast::ConstantDeclaration& d) {
    out += "(const";
    for (const auto& c : d.constants) {
      out += " " + c.name.name + " = ";
      (*this)(c.value);
    }
    out += ")\n";
  }
  void operator()(const ast::DataStatement& d) {
    out += fmt::format("(data \"{}\"", d.path);
    for (const auto& b : d.bindings) out += fmt::format(" {}{} = \"{}\"", b.signal.name.name, b.signal.primes, b.column);
    out += ")\n";
  }
  void operator()(const ast::Setting& s) { out += fmt::format("(set {} \"{}\")\n", s.key.name, s.value); }
  void operator()(const ast::WeightsSetting& s) {
    if (const auto* column = boost::get<std::string>(&s.value.get())) {
      out += fmt::format("(set weights (column \"{}\"))\n", *column);
    } else {
      out += "(set weights ";
      (*this)(boost::get<ast::Expression>(s.value.get()));
      out += ")\n";
    }
  }
  void operator()(const ast::PlotStatement& p) {
    out += fmt::format("(plot {}({}{}) ", p.name.name, p.argument.name.name, p.argument.primes);
    (*this)(p.fitted);
    if (p.truth) {
      out += " against ";
      (*this)(*p.truth);
    }
    out += ")\n";
  }
  void operator()(const ast::Equation& e) {
    out += "(= ";
    (*this)(e.lhs);
    out += "\n   ";
    (*this)(e.rhs);
    out += ")\n";
  }
};

}  // namespace

std::string print_ast(const ast::Model& model) {
  AstPrinter p;
  for (const auto& s : model.statements) boost::apply_visitor(p, s);
  return p.out;
}

}  // namespace sidc
