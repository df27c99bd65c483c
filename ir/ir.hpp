// The compiler's intermediate representation: canonical sums of products.
//
// Every expression of a model becomes a Sum of Terms; a Term is an exact coefficient times a
// product of Factors with integer powers (signals and their derivatives, time, functions, integrals,
// guards, ...). Sums are kept canonical by construction: factors sorted and merged, like terms
// added, zero terms dropped. Two operations are therefore the same exactly when their Sums compare
// equal, which is how identical operations are found and how the printer stays deterministic.
//
// A normalized Equation is the thesis' linear form (eq. 2-1.2): sum_k a_k * op_k = known, one
// Sum per parameter and one for the parameter-free terms. docs/compiler.md describes each field.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ir/number.hpp"
#include "ir/units.hpp"
#include "diagnostics/source.hpp"

namespace sidc::ir {

struct Sum;
using SumPtr = std::shared_ptr<const Sum>;

enum class Relation { less, less_equal, greater, greater_equal };

// `lhs relation rhs`, one condition of a guard.
struct Condition {
  SumPtr lhs;
  Relation relation = Relation::less;
  SumPtr rhs;
};

// The kinds of factor, in the order they are written within a term.
enum class FactorKind {
  parameter,      // a_k before normalize_pass splits the linear ones off; a nonlinear one (Parameter::nonlinear) stays
  test_function,  // phi_j and its derivatives (`order`): the weak form's test function on subdomain j
  signal,         // y, y', y'': `name`, derivative `order`
  initial_value,  // y(0), y'(t0): `name`, `order`, `at` (nullopt = t0); a constant read from the record
  window_start,   // t0, the start of the fit window (a constant)
  time,           // t
  elapsed,        // tau = t - t0, time since the start of the fit window
  function,       // sin, cos, exp, log, sqrt, abs, sign, tanh of `argument`
  power,          // argument^exponent that cannot be expanded (a sum to a negative or fractional power)
  derivative,     // der(argument, order) where no symbolic derivative exists; estimated from the data
  integral,       // int(argument): from t0 to t, evaluated numerically (eqs. 2-1.4, 2-2.5)
  guard,          // [conditions]: 1 where all hold, else 0 (eq. 4-1.9's regions)
};

struct Factor {
  FactorKind kind = FactorKind::signal;
  std::string name;           // parameter, signal, initial-value signal or function name
  int order = 0;              // derivative order; for parameters, their index in Model::parameters
  std::optional<Number> at;   // initial_value: the time, or nullopt for the window start t0
  Number exponent;            // power
  SumPtr argument;            // function, power, derivative, integral
  std::vector<Condition> conditions;  // guard

  // True when the factor does not change with time (t0, initial values, functions of those).
  bool is_constant_in_time() const;

  // A factor of `kind` with its name and order only (a signal, a parameter, t, ...).
  static Factor plain(FactorKind kind, std::string name = {}, int order = 0) { return Factor{kind, std::move(name), order, {}, {}, {}, {}}; }
};

int compare(const Factor& a, const Factor& b);
inline bool operator==(const Factor& a, const Factor& b) { return compare(a, b) == 0; }
inline bool operator<(const Factor& a, const Factor& b) { return compare(a, b) < 0; }

struct Term {
  Number coefficient{1};
  std::vector<std::pair<Factor, int>> factors;  // canonical: sorted by factor, powers merged, no zero powers
  Span span;  // where the term came from in the model text; not part of its identity

  bool is_number() const { return factors.empty(); }
};

// Canonical order of terms, comparing factors only (coefficients are what like terms add up).
int compare_factors(const Term& a, const Term& b);

struct Sum {
  std::vector<Term> terms;  // canonical: sorted, like terms merged, no zero coefficients

  bool empty() const { return terms.empty(); }
  std::optional<Number> as_number() const;  // the value if the sum is a plain number (0 if empty)
};

int compare(const Sum& a, const Sum& b);  // total order, coefficients included

// `<`, `<=`, `>`, `>=`: as written in the language (and in the compiled model file).
const char* to_string(Relation r);

// The highest derivative order anywhere in the sum, inside integrals, functions and guards too
// (a der() of a derivative adds up): what estimating it from data costs.
int highest_derivative_order(const Sum& s);
inline bool operator==(const Sum& a, const Sum& b) { return compare(a, b) == 0; }

// ---- construction and arithmetic (all results canonical) --------------------------------------
Sum number(const Number& n, const Span& span = {});
Sum factor(Factor f, int power = 1, const Span& span = {});
Sum add(const Sum& a, const Sum& b);
Sum negate(const Sum& a);
Sum subtract(const Sum& a, const Sum& b);
Sum scale(const Sum& a, const Number& k);
Sum multiply(const Sum& a, const Sum& b);
Term multiply(const Term& a, const Term& b);
Term canonical(Term t);  // sorts and merges factors of a hand-built term
Sum canonical(std::vector<Term> terms);
SumPtr share(Sum s);

// ---- the model ---------------------------------------------------------------------------------

struct Signal {
  enum class Kind { input, output };
  std::string name;
  Kind kind = Kind::output;
  Span span;
  std::optional<Sum> definition;  // an input given as an expression of t
  bool used = false;
  // How a recorded input moved between its samples (thesis section 4-2: a controller or a test
  // engineer sets a value and holds it). `smooth`: as a smooth curve through the samples (the
  // moving arc, Simpson's rule, the cubic of simulation); `held`: each sample's value holds until
  // the next (zero-order hold); `linear`: straight between samples (first-order hold). Integrals
  // of held and linear inputs are exact on each sample interval (runtime/operators/piecewise_inputs.hpp).
  enum class Hold { smooth, held, linear };
  Hold hold = Hold::smooth;
  Span hold_span;
  std::optional<Unit> unit;  // `output theta [rad]`; nullopt: none given
};

const char* to_string(Signal::Hold h);  // "smooth", "held", "linear"
std::optional<Signal::Hold> hold_from(std::string_view word);

struct Parameter {
  enum class Origin { declared, implicit, integration_constant };
  std::string name;
  Origin origin = Origin::declared;
  Span span;
  int equation = -1;  // for integration constants: the equation that introduced it
  // Derived by compiler/unit_pass.cpp from the signals' units; nullopt where some factor of its
  // term, or its equation's parameter-free side, has none.
  std::optional<Unit> unit;
  // `param L = 1.2`: the initial guess (a number; constants allowed in the model text).
  std::optional<Number> guess;
  // Set by lower_pass: the parameter stands inside a function, a power, a denominator or beside
  // another parameter (`sin(L*theta)`, `exp(-k*t)`, `y^p`), so it cannot be fitted by linear least
  // squares. It then stays a factor inside the operations (normalize_pass does not split it off):
  // the equation-error fit holds it at its guess (ir/fix_parameters.hpp) and `--refine` estimates it.
  bool nonlinear = false;
};

// How an equation is to be integrated (integrate_pass.cpp).
struct IntegrationRequest {
  enum class Count { fixed, automatic };
  Count count = Count::fixed;
  int times = 0;  // for `fixed`
  // Integration constants: fitted as new parameters (eqs. 2-1.5, 2-2.5), or taken from the record's
  // values at the window start, subtracted from each antiderivative (eqs. 2-1.4, 4-2.4).
  enum class Constants { fitted, initial };
  Constants constants = Constants::fitted;
  // `set form = weak`: integrated against test functions instead (weak_pass.cpp); count and times
  // are then unused. `set form` and `set integrate` set this request alike: the later one wins.
  bool weak = false;
  Span span;  // of the setting, for diagnostics
};

// sum_k a_k * op_k = known (eq. 2-1.2 written with the parameter-free terms on the right).
struct ParameterTerm {
  int parameter = 0;  // index into Model::parameters
  Sum operation;
};

struct Equation {
  Span span;
  std::vector<ParameterTerm> terms;  // in parameter order
  Sum known;
  IntegrationRequest integration;
  int integrations = 0;  // how many times integrate_pass integrated it
  // Weak form (weak_pass.cpp): every operation is a sum of phi_j^(k) * g terms, and the equation
  // holds integrated over each test function's subdomain j, one row per subdomain.
  bool weak = false;
};

// The moving-arc derivative operator and the other evaluation settings a model file can carry.
struct Settings {
  struct Value {
    std::string text;
    Span span;
  };
  std::map<std::string, Value> values;  // key -> raw value, as checked by declare_pass
};

// An exact derivative recorded beside an output (`y' = "ydot"`): compared with the moving-arc
// estimate in pictures (Figs. 4-1.8, 4-1.9), never used by the fit.
struct ExactDerivative {
  std::string signal;
  int order = 1;
  std::string column;
  Span span;
};

struct DataSource {
  std::string path;
  std::vector<std::pair<std::string, std::string>> bindings;  // signal (or "t") -> column
  std::vector<Span> binding_spans;
  std::vector<ExactDerivative> exact_derivatives;
  Span span;
};

// `set weights = <expression>`: each row's residual weighted by the expression's value on it
// (eq. 2-1.6). The column form `set weights = "w"` stays a setting (Settings::values).
struct WeightExpression {
  Sum value;
  Span span;
};

// `plot damper(y') = c1*y' + ... against ...`: a function of one signal built from the model's
// parameters, value = sum_k a_k * terms[k].operation + rest, drawn with the fitted values over the
// range the record covers; `truth` (no parameters) is what the user knows it should be.
struct PlotFunction {
  std::string name;
  Span span;
  std::string signal;  // the argument, and its derivative order
  int order = 0;
  std::vector<ParameterTerm> terms;  // in parameter order
  Sum rest;                          // the parameter-free part
  std::optional<Sum> truth;
};

struct Model {
  // No equation names its form (`set form`, `set integrate`, `--form`, `--integrate`) and the model
  // is dynamic: `sidc fit` chooses the form from the data (runtime/simulate/form_choice.hpp).
  bool form_from_data = false;
  std::string name;
  Span name_span;
  std::vector<Signal> signals;
  std::vector<Parameter> parameters;
  std::map<std::string, Number> constants;
  Settings settings;
  std::vector<DataSource> data;
  std::vector<Equation> equations;
  std::optional<WeightExpression> weights;
  std::vector<PlotFunction> plots;

  const Signal* signal(const std::string& name) const;
  Signal* signal(const std::string& name);
  int parameter_index(const std::string& name) const;  // -1 if absent
};

}  // namespace sidc::ir
