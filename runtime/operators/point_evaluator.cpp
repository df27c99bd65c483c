#include "runtime/operators/point_evaluator.hpp"

#include <algorithm>

#include <cmath>
#include <stdexcept>

#include "ir/print.hpp"
#include "diagnostics/model_catalogue.hpp"

namespace sidc {

int PointLayout::slot(const std::string& signal, int order) {
  if (auto found = find(signal, order)) return *found;
  slots_.emplace_back(signal, order);
  return static_cast<int>(slots_.size() - 1);
}

std::optional<int> PointLayout::find(const std::string& signal, int order) const {
  for (std::size_t i = 0; i < slots_.size(); ++i)
    if (slots_[i].second == order && slots_[i].first == signal) return static_cast<int>(i);
  return std::nullopt;
}

class PointSumCompiler {
 public:
  PointSumCompiler(PointSum& out, PointLayout& layout, const PointCompileOptions& options) : out_(out), layout_(layout), options_(options) {}

  // Compiles `s` into sums_[index] (reserved by the caller), depth first.
  std::optional<Diagnostic> compile(const ir::Sum& s, int index) {
    // Terms of one sum are contiguous; nested sums are compiled after, so collect first.
    const int first_term = static_cast<int>(out_.terms_.size());
    out_.sums_[static_cast<std::size_t>(index)] = {first_term, static_cast<int>(s.terms.size())};
    out_.terms_.resize(out_.terms_.size() + s.terms.size());
    for (std::size_t i = 0; i < s.terms.size(); ++i) {
      const ir::Term& t = s.terms[i];
      const int first_factor = static_cast<int>(out_.factors_.size());
      out_.factors_.resize(out_.factors_.size() + t.factors.size());
      out_.terms_[static_cast<std::size_t>(first_term) + i] = {t.coefficient.value(), first_factor, static_cast<int>(t.factors.size())};
      for (std::size_t n = 0; n < t.factors.size(); ++n) {
        PointSum::Factor compiled;
        if (auto d = factor(t.factors[n].first, t, compiled)) return d;
        compiled.power = t.factors[n].second;
        out_.factors_[static_cast<std::size_t>(first_factor) + n] = compiled;
      }
    }
    return std::nullopt;
  }

 private:
  int nested(const ir::Sum& s, std::optional<Diagnostic>& problem) {
    const int index = static_cast<int>(out_.sums_.size());
    out_.sums_.emplace_back();
    if (auto d = compile(s, index)) problem = d;
    return index;
  }

  std::optional<Diagnostic> factor(const ir::Factor& f, const ir::Term& t, PointSum::Factor& c) {
    using K = ir::FactorKind;
    using Op = PointSum::Op;
    std::optional<Diagnostic> problem;
    switch (f.kind) {
      case K::signal: c.op = Op::slot, c.index = layout_.slot(f.name, f.order); break;
      case K::time: c.op = Op::time; break;
      case K::elapsed: c.op = Op::elapsed; break;
      case K::window_start: c.op = Op::window_start; break;
      case K::initial_value: {
        std::optional<double> v = options_.initial_value ? options_.initial_value(f) : std::nullopt;
        if (!v) return diag::simulate_initial_value_term(t.span, print(f));
        c.op = Op::constant, c.value = *v;
        break;
      }
      case K::function: {
        const std::string& n = f.name;
        c.op = n == "sin" ? Op::sin : n == "cos" ? Op::cos : n == "exp" ? Op::exp : n == "log" ? Op::log : n == "sqrt" ? Op::sqrt
             : n == "abs" ? Op::abs : n == "tanh" ? Op::tanh : Op::sign;
        c.index = nested(*f.argument, problem);
        if (c.op == Op::sign) c.mode = mode_of(*f.argument);
        break;
      }
      case K::power:
        c.op = Op::power, c.value = f.exponent.value();
        c.index = nested(*f.argument, problem);
        break;
      case K::guard: {
        c.op = Op::guard;
        c.index = static_cast<int>(out_.conditions_.size());
        c.count = static_cast<int>(f.conditions.size());
        out_.conditions_.resize(out_.conditions_.size() + f.conditions.size());
        for (std::size_t i = 0; i < f.conditions.size(); ++i) {
          PointSum::Condition cond;
          cond.relation = f.conditions[i].relation;
          cond.lhs = nested(*f.conditions[i].lhs, problem);
          cond.rhs = nested(*f.conditions[i].rhs, problem);
          cond.mode = mode_of(ir::subtract(*f.conditions[i].lhs, *f.conditions[i].rhs));
          out_.conditions_[static_cast<std::size_t>(c.index) + i] = cond;
        }
        break;
      }
      case K::integral: return diag::simulate_integral(t.span, print(f));
      case K::derivative: return diag::simulate_estimated_derivative(t.span, print(f));
      case K::parameter: throw std::logic_error("a parameter factor reached the point evaluator");
      case K::test_function: throw std::logic_error("a test function reached the point evaluator (simulation solves the normalized model)");
    }
    return problem;
  }

  // The switching function this condition or sign() argument is, for frozen modes; -1 if none.
  int mode_of(const ir::Sum& g) const {
    const auto& list = options_.switching_functions;
    const auto it = std::find(list.begin(), list.end(), g);
    return it == list.end() ? -1 : static_cast<int>(it - list.begin());
  }

  PointSum& out_;
  PointLayout& layout_;
  const PointCompileOptions& options_;
};

std::variant<PointSum, Diagnostic> compile_point_sum(const ir::Sum& s, PointLayout& layout, const PointCompileOptions& options) {
  PointSum out;
  out.sums_.emplace_back();
  PointSumCompiler compiler(out, layout, options);
  if (auto d = compiler.compile(s, 0)) return *d;
  return out;
}

namespace {

// x^n for a factor's integer power by multiplication: std::pow's general algorithm costs more than
// the rest of a right-hand side evaluation (y^3 in a Duffing term), and is no more exact for small n.
double integer_power(double x, int n) {
  if (n == 1) return x;
  if (n < 0 || n > 8) return std::pow(x, n);
  double p = 1;
  for (int k = 0; k < n; ++k) p *= x;
  return p;
}

}  // namespace

double PointSum::factor(const Factor& f, const PointInstant& at) const {
  switch (f.op) {
    case Op::slot: return at.slots[static_cast<std::size_t>(f.index)];
    case Op::time: return at.t;
    case Op::elapsed: return at.t - at.t0;
    case Op::window_start: return at.t0;
    case Op::constant: return f.value;
    case Op::sin: return std::sin(sum(f.index, at));
    case Op::cos: return std::cos(sum(f.index, at));
    case Op::exp: return std::exp(sum(f.index, at));
    case Op::log: return std::log(sum(f.index, at));
    case Op::sqrt: return std::sqrt(sum(f.index, at));
    case Op::abs: return std::abs(sum(f.index, at));
    case Op::tanh: return std::tanh(sum(f.index, at));
    case Op::sign: {
      if (f.mode >= 0 && static_cast<std::size_t>(f.mode) < at.modes.size() && at.modes[static_cast<std::size_t>(f.mode)] != kLiveMode)
        return at.modes[static_cast<std::size_t>(f.mode)];
      const double x = sum(f.index, at);
      return std::isnan(x) ? x : static_cast<double>((x > 0) - (x < 0));
    }
    case Op::power: return std::pow(sum(f.index, at), f.value);
    case Op::guard: {
      for (int i = 0; i < f.count; ++i) {
        const Condition& c = conditions_[static_cast<std::size_t>(f.index + i)];
        if (c.mode >= 0 && static_cast<std::size_t>(c.mode) < at.modes.size() && at.modes[static_cast<std::size_t>(c.mode)] != kLiveMode) {
          const int m = at.modes[static_cast<std::size_t>(c.mode)];  // the sign of lhs - rhs, frozen
          const bool frozen = c.relation == ir::Relation::less ? m < 0
                            : c.relation == ir::Relation::less_equal ? m <= 0
                            : c.relation == ir::Relation::greater ? m > 0 : m >= 0;
          if (!frozen) return 0.0;
          continue;
        }
        const double l = sum(c.lhs, at), r = sum(c.rhs, at);
        if (std::isnan(l) || std::isnan(r)) return std::numeric_limits<double>::quiet_NaN();
        const bool holds = c.relation == ir::Relation::less ? l < r
                         : c.relation == ir::Relation::less_equal ? l <= r
                         : c.relation == ir::Relation::greater ? l > r : l >= r;
        if (!holds) return 0.0;
      }
      return 1.0;
    }
  }
  return 0.0;
}

double PointSum::sum(int index, const PointInstant& at) const {
  const Range& s = sums_[static_cast<std::size_t>(index)];
  double total = 0;
  for (int i = 0; i < s.count; ++i) {
    const Term& t = terms_[static_cast<std::size_t>(s.first + i)];
    double v = t.coefficient;
    for (int n = 0; n < t.count; ++n) {
      const Factor& f = factors_[static_cast<std::size_t>(t.first + n)];
      const double x = factor(f, at);
      if (f.op == Op::guard) {
        if (x == 0.0) {
          v = 0.0;
          break;  // a guard that is off zeroes the term whatever the other factors are
        }
        v *= x;
        continue;
      }
      const double p = integer_power(x, f.power);
      if (v != 0.0 || std::isnan(p)) v *= p;
    }
    total += v;
  }
  return total;
}

}  // namespace sidc
