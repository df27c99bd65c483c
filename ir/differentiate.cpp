#include "ir/differentiate.hpp"

#include <limits>
#include <map>

namespace sidc {
namespace {

using ir::Factor;
using ir::FactorKind;
using ir::Sum;

Sum function_of(const std::string& name, const Sum& argument) {
  return ir::factor(Factor{FactorKind::function, name, 0, {}, {}, ir::share(argument), {}});
}

// What a derivative is taken with respect to: time (no signal, no parameter), one signal
// derivative y^(m) held as an independent variable, as in the Jacobian of an ODE's right-hand
// side, or one parameter (its index), as in the sensitivity to a nonlinear parameter.
struct Variable {
  const std::string* signal = nullptr;
  int order = 0;
  ir::NodeBudget* budget = nullptr;  // none: unbounded
  int parameter = -1;
  bool in_time() const { return signal == nullptr && parameter < 0; }
};

std::optional<Sum> derivative_of(const Sum& s, const Variable& v);
std::optional<Sum> derivative_of(const ir::Term& t, const Variable& v);

// d/dt or the partial derivative of a single factor (power 1), or nullopt.
std::optional<Sum> derivative_of(const Factor& f, const Variable& v) {
  const bool in_time = v.in_time();
  switch (f.kind) {
    case FactorKind::parameter:
      return v.parameter >= 0 && f.order == v.parameter ? ir::number(1) : Sum{};
    case FactorKind::window_start:
    case FactorKind::initial_value: return Sum{};
    case FactorKind::signal: {
      if (!in_time) return v.signal && f.name == *v.signal && f.order == v.order ? ir::number(1) : Sum{};
      Factor next = f;
      ++next.order;
      return ir::factor(next);
    }
    case FactorKind::time:
    case FactorKind::elapsed: return in_time ? ir::number(1) : Sum{};
    case FactorKind::integral:  // d/dt int(u) = u; a partial derivative of an integral has no value at a point
      if (!in_time) return std::nullopt;
      return *f.argument;
    case FactorKind::test_function:  // phi_j^(k)' = phi_j^(k+1), known exactly
      if (!in_time) return Sum{};
      [[fallthrough]];
    case FactorKind::derivative: {
      if (!in_time) return std::nullopt;
      Factor next = f;
      ++next.order;
      return ir::factor(next);
    }
    // A guard is constant between its switches: its partial derivative is 0 there, which is what
    // the Jacobian of a right-hand side needs; in time it jumps, and d/dt has no Sum.
    case FactorKind::guard:
      if (!in_time) return Sum{};
      return std::nullopt;
    case FactorKind::power: {  // (u^e)' = e u^(e-1) u'
      auto du = derivative_of(*f.argument, v);
      if (!du) return std::nullopt;
      auto lowered = raise(*f.argument, f.exponent - Number(1));
      if (!lowered) return std::nullopt;
      return ir::scale(ir::multiply(*lowered, *du), f.exponent);
    }
    case FactorKind::function: {
      const Sum& u = *f.argument;
      auto du = derivative_of(u, v);
      if (!du) return std::nullopt;
      Sum outer;
      if (f.name == "sin") outer = function_of("cos", u);
      else if (f.name == "cos") outer = ir::negate(function_of("sin", u));
      else if (f.name == "exp") outer = function_of("exp", u);
      else if (f.name == "log") outer = reciprocal(u);
      else if (f.name == "sqrt") outer = ir::scale(reciprocal(function_of("sqrt", u)), Number::rational(1, 2));
      else if (f.name == "tanh") {
        const Sum th = function_of("tanh", u);
        outer = ir::subtract(ir::number(1), ir::multiply(th, th));
      } else if (f.name == "abs") outer = function_of("sign", u);
      else if (f.name == "sign" && !in_time) return Sum{};  // constant between its jumps, like a guard
      else return std::nullopt;  // sign() jumps
      return ir::multiply(outer, *du);
    }
  }
  return std::nullopt;
}

}  // namespace

Sum reciprocal(const Sum& u) {
  if (u.terms.size() == 1 && u.terms[0].coefficient.exact()) {
    ir::Term t = u.terms[0];
    t.coefficient = Number(1) / t.coefficient;
    for (auto& f : t.factors) f.second = -f.second;
    return ir::canonical(std::vector<ir::Term>{ir::canonical(t)});
  }
  return ir::factor(Factor{FactorKind::power, "", 0, {}, Number(-1), ir::share(u), {}});
}

namespace {

// True when the exponent vectors of u's terms (the power of each distinct factor) are affinely
// independent: then no two products of e terms coincide, and u^e has exactly C(e + n - 1, n - 1)
// terms. Gaussian elimination on at most a few hundred small integer vectors.
bool independent_terms(const Sum& u) {
  std::map<Factor, std::size_t> column;
  for (const auto& t : u.terms)
    for (const auto& [f, power] : t.factors) column.emplace(f, column.size());
  const std::size_t n = u.terms.size();
  if (column.size() + 1 < n) return false;  // more terms than dimensions + 1: dependent
  std::vector<std::vector<long double>> rows(n, std::vector<long double>(column.size(), 0.0L));
  for (std::size_t i = 0; i < n; ++i)
    for (const auto& [f, power] : u.terms[i].factors) rows[i][column.at(f)] = power;
  for (std::size_t i = 1; i < n; ++i)
    for (std::size_t j = 0; j < column.size(); ++j) rows[i][j] -= rows[0][j];
  std::size_t rank = 0;
  for (std::size_t j = 0; j < column.size() && rank + 1 < n; ++j) {
    std::size_t pivot = rank + 1;
    while (pivot < n && rows[pivot][j] == 0.0L) ++pivot;
    if (pivot == n) continue;
    std::swap(rows[pivot], rows[rank + 1]);
    for (std::size_t i = rank + 2; i < n; ++i) {
      const long double k = rows[i][j] / rows[rank + 1][j];
      for (std::size_t c = j; c < column.size(); ++c) rows[i][c] -= k * rows[rank + 1][c];
    }
    ++rank;
  }
  return rank + 1 == n;
}

// C(e + n - 1, n - 1), or anything above `cap` once it passes it.
long double multinomial_terms(std::size_t n, std::int64_t e, std::size_t cap) {
  long double c = 1;
  for (std::size_t k = 1; k < n; ++k) {
    c = c * static_cast<long double>(e + static_cast<std::int64_t>(k)) / static_cast<long double>(k);
    if (c > static_cast<long double>(cap)) return c;
  }
  return c;
}

}  // namespace

std::optional<Sum> raise(const Sum& u, const Number& e, std::size_t max_terms, ir::NodeBudget* budget) {
  if (e.is_zero()) return ir::number(1);
  if (e.is_integer() && e.numerator() > 0) {
    // Predicted at once where the count is exact; beyond a few hundred terms u^2 alone is too many.
    if (u.terms.size() > 1 && u.terms.size() <= 256 && e.numerator() > 1 &&
        multinomial_terms(u.terms.size(), e.numerator(), max_terms) > static_cast<long double>(max_terms) && independent_terms(u))
      return std::nullopt;
    // One term: its powers multiplied at once, where the coefficient stays exact (then it is
    // what e multiplications would give). Multiplying y by itself k times for every y^k of a
    // `sum(k = 1..n, c[k]*y^k)` was quadratic in n.
    if (u.terms.size() == 1 && u.terms[0].coefficient.exact()) {
      const ir::Term& t = u.terms[0];
      const Number coefficient = t.coefficient.pow(e.numerator());
      if (coefficient.exact()) {
        ir::Term raised{coefficient, {}, t.span};
        for (const auto& [f, power] : t.factors) {
          const long double p = static_cast<long double>(power) * static_cast<long double>(e.numerator());
          if (p > std::numeric_limits<int>::max() / 2 || p < std::numeric_limits<int>::min() / 2) return std::nullopt;
          raised.factors.push_back({f, static_cast<int>(p)});
        }
        return ir::canonical(std::vector<ir::Term>{ir::canonical(std::move(raised))});
      }
    }
    Sum result = ir::number(1);
    for (std::int64_t k = 0; k < e.numerator(); ++k) {
      if (result.terms.size() * u.terms.size() > max_terms) return std::nullopt;
      if (budget && !budget->spend(result.terms.size() * u.terms.size())) return std::nullopt;
      result = ir::multiply(result, u);
    }
    return result;
  }
  if (e.is_integer() && u.terms.size() == 1) {  // a single term to a negative power
    Sum inverse = reciprocal(u);
    return raise(inverse, -e, max_terms, budget);
  }
  if (u.empty()) return Sum{};
  // A single atomic factor to a fractional power stays one factor: y^1.5.
  return ir::factor(Factor{FactorKind::power, "", 0, {}, e, ir::share(u), {}});
}

namespace {

std::optional<Sum> derivative_of(const ir::Term& t, const Variable& v) {
  std::vector<ir::Term> terms;
  for (std::size_t i = 0; i < t.factors.size(); ++i) {
    const auto& [f, power] = t.factors[i];
    auto df = derivative_of(f, v);
    if (!df) return std::nullopt;
    // d(f^k) = k f^(k-1) f', times the other factors.
    ir::Term rest{t.coefficient * Number(power), {}, t.span};
    for (std::size_t j = 0; j < t.factors.size(); ++j)
      rest.factors.push_back(j == i ? std::pair{f, power - 1} : t.factors[j]);
    rest = ir::canonical(rest);
    for (const auto& dt : df->terms) {
      terms.push_back(ir::multiply(rest, dt));
      if (v.budget && !v.budget->spend(ir::written_nodes(terms.back(), v.budget->remaining()))) return std::nullopt;
    }
  }
  return ir::canonical(std::move(terms));
}

std::optional<Sum> derivative_of(const Sum& s, const Variable& v) {
  std::vector<ir::Term> terms;
  for (const auto& t : s.terms) {
    auto dt = derivative_of(t, v);
    if (!dt) return std::nullopt;
    terms.insert(terms.end(), dt->terms.begin(), dt->terms.end());
  }
  return ir::canonical(std::move(terms));
}

}  // namespace

std::optional<Sum> differentiate(const ir::Term& t) { return derivative_of(t, Variable{}); }

std::optional<Sum> differentiate(const Sum& s, int times) {
  Sum current = s;
  for (int k = 0; k < times; ++k) {
    auto next = derivative_of(current, Variable{});
    if (!next) return std::nullopt;
    current = std::move(*next);
  }
  return current;
}

std::optional<Sum> differentiate(const Sum& s, int times, ir::NodeBudget& budget) {
  Sum current = s;
  for (int k = 0; k < times; ++k) {
    auto next = derivative_of(current, Variable{nullptr, 0, &budget, -1});
    if (!next) return std::nullopt;
    current = std::move(*next);
  }
  return current;
}

std::optional<Sum> partial_derivative(const Sum& s, const std::string& signal, int order) {
  return derivative_of(s, Variable{&signal, order, nullptr, -1});
}

std::optional<ir::Sum> partial_derivative_by_parameter(const ir::Sum& s, int parameter) {
  return derivative_of(s, Variable{nullptr, 0, nullptr, parameter});
}

}  // namespace sidc
