// What declare_pass.cpp hands to lower_pass.cpp: the model's names, settings and data statements,
// and the parts of the AST still to be lowered (constants, input definitions, equations).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "ir/ir.hpp"
#include "grammar/ast.hpp"

namespace sidc {

struct Declarations {
  ir::Model model;  // name, signals, declared parameters (families expanded), settings, data
  std::map<std::string, std::pair<int, int>> families;  // declared parameter families: name -> range
  bool parameters_declared = false;
  std::map<std::string, Span> names;  // every declared name, for "declared twice" and "did you mean"

  struct Constant {
    std::string name;
    const ast::Expression* value;
    Span span;
  };
  std::vector<Constant> constants;  // in order: each may use the ones before it

  // `param L = 1.2`: the guesses, lowered after the constants (a guess may use them). A family's
  // guess is every member's: parameters [first, first + count).
  struct Guess {
    std::size_t first = 0, count = 1;
    const ast::Expression* value = nullptr;
  };
  std::vector<Guess> guesses;

  struct InputDefinition {
    std::size_t signal;
    const ast::Expression* definition;
  };
  std::vector<InputDefinition> input_definitions;

  struct PendingEquation {
    const ast::Equation* equation;
    ir::IntegrationRequest integration;  // from the `integrate`/`constants` settings before it
  };
  std::vector<PendingEquation> equations;

  const ast::Expression* weights = nullptr;  // `set weights = <expression>`
  Span weights_span;
  std::vector<const ast::PlotStatement*> plots;
};

// Names no model may declare: the time variables, pi, the functions and the operators.
bool is_builtin_name(const std::string& name);
bool is_function_name(const std::string& name);
const std::vector<std::string>& function_names();

}  // namespace sidc
