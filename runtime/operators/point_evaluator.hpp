// Evaluation of a compiled Sum at one instant: the right-hand side of an ODE, or a model's
// nonlinear function drawn over a range (runtime/operators/evaluate.hpp does whole records instead).
//
// Relies on: ir/ir.hpp Sums after normalization (no parameter factors). Guarantees:
// compile_point_sum() turns a Sum into a flat program once (terms, factors and nested sums in
// arrays, signal values looked up by slot index, function names resolved to an enum), so that an
// evaluation does no map lookup, no string compare and no allocation. Signals and their
// derivatives are read from a caller-filled array of slots, laid out by a PointLayout that the
// compilation extends; t, t0 and tau = t - t0 are passed with it. Guards are 1 where all their
// conditions hold, else 0, and a guard that is off zeroes its term even where another factor is
// not finite (as runtime/operators/evaluate.cpp does, eq. 4-1.9). int() and der() have no value at a point:
// compiling them is a Diagnostic, as is an initial value (`y(0)`) the caller cannot resolve.
#pragma once

#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "ir/ir.hpp"
#include "diagnostics/diagnostic.hpp"

namespace sidc {

// Which slot of the value array holds which signal derivative.
class PointLayout {
 public:
  int slot(const std::string& signal, int order);  // the slot, added if new
  std::optional<int> find(const std::string& signal, int order) const;
  std::size_t size() const { return slots_.size(); }
  const std::vector<std::pair<std::string, int>>& slots() const { return slots_; }  // (signal, order) by slot

 private:
  std::vector<std::pair<std::string, int>> slots_;
};

// A frozen mode that is not frozen: the condition or sign() is evaluated as usual.
inline constexpr signed char kLiveMode = 2;

// One instant: slot values (PointLayout order), the time t and the window start t0; and, while a
// solver takes one step, the frozen modes: per switching function (PointCompileOptions), the sign
// of its value at the step's start (-1, 0, 1, or kLiveMode), which every guard condition and sign()
// built on it then uses instead of its value, so that a step that ends on a switch never samples
// the next branch in its last stage (a discontinuous right-hand side inside an RK4 step costs it
// its order, and the sensitivities their meaning). Empty: everything live.
struct PointInstant {
  std::span<const double> slots;
  double t = 0;
  double t0 = 0;
  std::span<const signed char> modes;
};

class PointSum {
 public:
  double evaluate(const PointInstant& at) const { return sum(0, at); }
  bool is_zero() const { return sums_.empty() || sums_[0].count == 0; }

 private:
  friend class PointSumCompiler;
  friend std::variant<PointSum, Diagnostic> compile_point_sum(const ir::Sum&, PointLayout&, const struct PointCompileOptions&);
  enum class Op : unsigned char { slot, time, elapsed, window_start, constant, sin, cos, exp, log, sqrt, abs, sign, tanh, power, guard };
  struct Factor {
    Op op = Op::constant;
    int power = 1;         // integer power of the factor in its term
    int index = 0;         // slot, or nested sum (function/power), or first condition (guard)
    int count = 0;         // guard: number of conditions
    int mode = -1;         // sign(): the switching function its argument is, or -1
    double value = 0;      // constant; power: exponent
  };
  struct Term {
    double coefficient = 1;
    int first = 0, count = 0;  // factors
  };
  struct Range {
    int first = 0, count = 0;  // terms
  };
  struct Condition {
    int lhs = 0, rhs = 0;  // nested sums
    ir::Relation relation = ir::Relation::less;
    int mode = -1;  // the switching function lhs - rhs is, or -1
  };
  double sum(int index, const PointInstant& at) const;
  double factor(const Factor& f, const PointInstant& at) const;

  std::vector<Range> sums_;  // sums_[0] is the compiled sum itself
  std::vector<Term> terms_;
  std::vector<Factor> factors_;
  std::vector<Condition> conditions_;
};

struct PointCompileOptions {
  // The value of an initial-value factor such as `y(0)` or `y'(t0)`; nullopt when it has none
  // (compilation then fails with a Diagnostic at the term). Unset: every such factor fails.
  std::function<std::optional<double>(const ir::Factor&)> initial_value;
  // The switching functions whose frozen modes PointInstant::modes gives (ExplicitForm::
  // switching_functions): a guard condition `lhs rel rhs` whose lhs - rhs, or a sign() whose
  // argument, is one of them reads its mode there.
  std::vector<ir::Sum> switching_functions;
};

// Compiles `s`; new signal derivatives get slots in `layout`.
std::variant<PointSum, Diagnostic> compile_point_sum(const ir::Sum& s, PointLayout& layout, const PointCompileOptions& options = {});

}  // namespace sidc
