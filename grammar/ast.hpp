// The abstract syntax tree of a `.sid` model file, exactly as written.
//
// The tree keeps the user's structure (precedence levels as nested Expressions, as in Spirit X3's
// calc examples) and every node's position (x3::position_tagged; the error handler records
// each node's byte range, and ParseResult::span turns it into a Span). It makes no judgement of meaning: whether `c[k]` names a parameter or
// `y(0)` an initial value is decided by compiler/declare_pass.cpp and compiler/lower_pass.cpp. docs/language.md is the
// specification, with the EBNF this tree follows.
#pragma once

#include <boost/spirit/home/x3/support/ast/position_tagged.hpp>
#include <boost/spirit/home/x3/support/ast/variant.hpp>
#include <optional>
#include <string>
#include <vector>

namespace sidc::ast {

namespace x3 = boost::spirit::x3;

// A name as written, e.g. `a1`, `y`, `sin`.
struct Identifier : x3::position_tagged {
  std::string name;
};

// A numeric literal, kept as its text so that the compiler can read it exactly (`0.005` is the
// rational 1/200, not the nearest double).
struct Number : x3::position_tagged {
  std::string text;
};

// A name followed by primes: `y` (primes = 0), `y'`, `y''`. Time derivative of that order.
struct Variable : x3::position_tagged {
  Identifier name;
  std::string primes;  // "", "'", "''", ...: its size is the derivative order
};

struct Expression;
struct Signed;
struct Call;
struct Indexed;
struct Guard;
struct SumOver;

struct Operand : x3::variant<Number, Variable, x3::forward_ast<Signed>, x3::forward_ast<Call>,
                             x3::forward_ast<Indexed>, x3::forward_ast<Guard>, x3::forward_ast<SumOver>,
                             x3::forward_ast<Expression>> {
  using base_type::base_type;
  using base_type::operator=;
};

// Unary minus (or plus): `-y`.
struct Signed : x3::position_tagged {
  char sign = '-';
  Operand operand;
};

// One binary step `op operand` of an Expression; op is one of + - * / ^.
struct Operation : x3::position_tagged {
  char op = '+';
  Operand operand;
};

// `first op1 operand1 op2 operand2 ...`, all at one precedence level (the grammar nests levels:
// an additive Expression's operands are multiplicative Expressions, and so on). `^` steps hold a
// single right operand, which makes `y^2^3` = y^(2^3).
struct Expression : x3::position_tagged {
  Operand first;
  std::vector<Operation> rest;
};

// `name(arg, ...)`: a function (sin, cos, exp, log, sqrt, abs, sign, tanh), `der(e, n)`,
// `int(e)`, or an initial value such as `y(0)` / `y'(0)`. The callee may carry primes
// (`y'(0)`), hence a Variable.
struct Call : x3::position_tagged {
  Variable callee;
  std::vector<Expression> arguments;
};

// `name[index]`: a member of an indexed parameter family, `c[3]` or `c[k + 6]` inside a sum.
struct Indexed : x3::position_tagged {
  Identifier name;
  Expression index;
};

// `lhs <= rhs`; op is one of "<", "<=", ">", ">=".
struct Comparison : x3::position_tagged {
  Expression lhs;
  std::string op;
  Expression rhs;
};

// An Iverson bracket `[y' <= 0 and y > 0]`: 1 where every comparison holds, 0 elsewhere.
struct Guard : x3::position_tagged {
  std::vector<Comparison> conditions;
};

// `sum(k = 1..6, c[k]*y'^k)`: the body repeated for every integer k in the range.
struct SumOver : x3::position_tagged {
  Identifier index;
  int from = 0;
  int to = 0;
  Expression body;
};

// ---- statements -------------------------------------------------------------------------------

// `model quasi_linear`
struct ModelName : x3::position_tagged {
  Identifier name;
};

// `[N*m]` after a signal's name: its unit, kept as text and read by compiler/declare_pass.cpp
// (ir/units.hpp), which reports a bad unit at its own column.
struct UnitText : x3::position_tagged {
  std::string text;
  std::size_t offset = 0;  // byte offset of the text in the source
};

// One signal of an `input`/`output` declaration, with its unit if given (`output theta [rad]`); an
// input may be given as an expression of t (`input x = 60*sin(4*pi*t)`, as the thesis evaluated
// its excitation) or carry how it was held between samples (`input x held`; the word is checked
// by compiler/declare_pass.cpp).
struct SignalItem : x3::position_tagged {
  Identifier name;
  std::optional<UnitText> unit;
  std::optional<Identifier> hold;
  std::optional<Expression> definition;
};

// `input x1, x2` or `output y`
struct SignalDeclaration : x3::position_tagged {
  std::string kind;  // "input" or "output"
  std::vector<SignalItem> signals;
};

// One item of `param a1, c[1..6], L = 1.2`: a single parameter or an indexed family, with an
// optional initial guess (a parameter that enters nonlinearly needs one).
struct ParameterItem : x3::position_tagged {
  Identifier name;
  std::optional<int> from;  // both set for a family c[from..to]
  std::optional<int> to;
  std::optional<Expression> guess;
};

struct ParameterDeclaration : x3::position_tagged {
  std::vector<ParameterItem> parameters;
};

// `const g = 9.81, L = 2*g`
struct ConstantItem : x3::position_tagged {
  Identifier name;
  Expression value;
};

struct ConstantDeclaration : x3::position_tagged {
  std::vector<ConstantItem> constants;
};

// `y = "displacement"` inside a data statement: signal (or `t`) bound to a column by name.
// `y' = "velocity"` binds an exact derivative of an output, recorded alongside it: never fitted,
// only compared with the moving-arc estimate (the thesis' Figs. 4-1.8 and 4-1.9).
struct ColumnBinding : x3::position_tagged {
  Variable signal;
  std::string column;
};

// `data "appendix_a.csv" (t = "t", x = "x", y = "y")`; without bindings, columns are looked up
// by the signals' own names and the time column is `t`. Several data statements are several
// records (experiments) fitted together.
struct DataStatement : x3::position_tagged {
  std::string path;
  std::vector<ColumnBinding> bindings;
};

// `set integrate = 1`: the value is kept as text (trimmed, without the comment) and checked by
// the compiler, which knows each setting's values. Settings `integrate` and `constants` apply to
// the equations that follow them; the others to the whole model.
struct Setting : x3::position_tagged {
  Identifier key;
  std::string value;
  std::size_t value_offset = 0;  // byte offset of the value in the source, for diagnostics
};

// `set weights = "w"` (a record column) or `set weights = 1/(1 + y'^2)` (an expression of the
// signals and t): the weight of each row's residual, eq. 2-1.6.
struct WeightsValue : x3::variant<std::string, Expression> {
  using base_type::base_type;
  using base_type::operator=;
};

struct WeightsSetting : x3::position_tagged {
  WeightsValue value;
};

// `plot damper(y') = c1*y' + c2*y'^3 against 0.5*y' + y'^3`: a function of one signal made of
// the model's parameters (the damper force of eq. 4-1.1), drawn over the range the record covers
// with the fitted values, optionally against a truth the user knows (Figs. 4-1.13, 4-1.14).
struct PlotStatement : x3::position_tagged {
  Identifier name;
  Variable argument;
  Expression fitted;
  std::optional<Expression> truth;
};

// `lhs = rhs`
struct Equation : x3::position_tagged {
  Expression lhs;
  Expression rhs;
};

struct Statement : x3::variant<ModelName, SignalDeclaration, ParameterDeclaration, ConstantDeclaration,
                               DataStatement, WeightsSetting, Setting, PlotStatement, Equation> {
  using base_type::base_type;
  using base_type::operator=;
};

struct Model {
  std::vector<Statement> statements;
};

}  // namespace sidc::ast
