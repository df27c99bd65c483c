#include "ir/ir.hpp"

#include <algorithm>
#include <cctype>

#include "ir/traversal.hpp"

namespace sidc::ir {
namespace {

template <class T>
int three_way(const T& a, const T& b) {
  return a < b ? -1 : (b < a ? 1 : 0);
}

// Natural order of names, so that y2 sorts before y10.
int compare_names(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      std::size_t i2 = i, j2 = j;
      while (i2 < a.size() && std::isdigit(static_cast<unsigned char>(a[i2]))) ++i2;
      while (j2 < b.size() && std::isdigit(static_cast<unsigned char>(b[j2]))) ++j2;
      const std::string_view da = std::string_view(a).substr(i, i2 - i), db = std::string_view(b).substr(j, j2 - j);
      const auto ta = da.substr(std::min(da.find_first_not_of('0'), da.size()));
      const auto tb = db.substr(std::min(db.find_first_not_of('0'), db.size()));
      if (ta.size() != tb.size()) return ta.size() < tb.size() ? -1 : 1;
      if (int c = ta.compare(tb)) return c < 0 ? -1 : 1;
      i = i2, j = j2;
      continue;
    }
    if (a[i] != b[j]) return a[i] < b[j] ? -1 : 1;
    ++i, ++j;
  }
  return three_way(a.size() - i, b.size() - j);
}

int compare_ptr(const SumPtr& a, const SumPtr& b) {
  if (!a || !b) return three_way(a != nullptr, b != nullptr);
  return compare(*a, *b);
}

}  // namespace

bool Factor::is_constant_in_time() const {
  // t0 and initial values are constants; a function or power is one when nothing but those (and
  // functions and powers of them) stands anywhere inside it.
  const auto varies = [](const Factor& f) {
    return f.kind != FactorKind::window_start && f.kind != FactorKind::initial_value && f.kind != FactorKind::function &&
           f.kind != FactorKind::power;
  };
  return !varies(*this) && !(argument && any_factor(*argument, varies));
}

int compare(const Factor& a, const Factor& b) {
  if (a.kind != b.kind) return three_way(static_cast<int>(a.kind), static_cast<int>(b.kind));
  switch (a.kind) {
    case FactorKind::parameter: return three_way(a.order, b.order);
    case FactorKind::signal:
      if (int c = compare_names(a.name, b.name)) return c;
      return three_way(b.order, a.order);  // y'' before y' before y
    case FactorKind::time:
    case FactorKind::elapsed:
    case FactorKind::window_start: return 0;
    case FactorKind::initial_value:
      if (int c = compare_names(a.name, b.name)) return c;
      if (a.order != b.order) return three_way(b.order, a.order);
      if (a.at.has_value() != b.at.has_value()) return a.at.has_value() ? 1 : -1;
      return a.at ? compare(*a.at, *b.at) : 0;
    case FactorKind::function:
      if (int c = a.name.compare(b.name)) return c < 0 ? -1 : 1;
      return compare_ptr(a.argument, b.argument);
    case FactorKind::power:
      if (int c = compare_ptr(a.argument, b.argument)) return c;
      return compare(a.exponent, b.exponent);
    case FactorKind::derivative:
      if (a.order != b.order) return three_way(b.order, a.order);
      return compare_ptr(a.argument, b.argument);
    case FactorKind::integral: return compare_ptr(a.argument, b.argument);
    case FactorKind::test_function: return three_way(a.order, b.order);
    case FactorKind::guard: {
      const std::size_t n = std::min(a.conditions.size(), b.conditions.size());
      for (std::size_t i = 0; i < n; ++i) {
        const auto& x = a.conditions[i];
        const auto& y = b.conditions[i];
        if (int c = compare_ptr(x.lhs, y.lhs)) return c;
        if (x.relation != y.relation) return three_way(static_cast<int>(x.relation), static_cast<int>(y.relation));
        if (int c = compare_ptr(x.rhs, y.rhs)) return c;
      }
      return three_way(a.conditions.size(), b.conditions.size());
    }
  }
  return 0;
}

int compare_factors(const Term& a, const Term& b) {
  // Plain numbers sort last, as the thesis writes its constants (eq. 2-2.9: `... + a4 t + a5`), and
  // before them other terms constant in time (`t^2/2 - t0^2/2`, `y - y(t0)`).
  if (a.factors.empty() != b.factors.empty()) return a.factors.empty() ? 1 : -1;
  auto constant = [](const Term& t) {
    return std::all_of(t.factors.begin(), t.factors.end(), [](const auto& f) {
      return f.first.kind == FactorKind::parameter || f.first.is_constant_in_time();
    });
  };
  if (constant(a) != constant(b)) return constant(a) ? 1 : -1;
  const std::size_t n = std::min(a.factors.size(), b.factors.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (int c = compare(a.factors[i].first, b.factors[i].first)) return c;
    if (a.factors[i].second != b.factors[i].second) return three_way(a.factors[i].second, b.factors[i].second);
  }
  return three_way(a.factors.size(), b.factors.size());
}

int compare(const Sum& a, const Sum& b) {
  const std::size_t n = std::min(a.terms.size(), b.terms.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (int c = compare_factors(a.terms[i], b.terms[i])) return c;
    if (int c = compare(a.terms[i].coefficient, b.terms[i].coefficient)) return c;
  }
  return three_way(a.terms.size(), b.terms.size());
}

const char* to_string(Relation r) {
  switch (r) {
    case Relation::less: return "<";
    case Relation::less_equal: return "<=";
    case Relation::greater: return ">";
    case Relation::greater_equal: return ">=";
  }
  return "<";
}

const char* to_string(Signal::Hold h) {
  switch (h) {
    case Signal::Hold::smooth: return "smooth";
    case Signal::Hold::held: return "held";
    case Signal::Hold::linear: return "linear";
  }
  return "smooth";
}

std::optional<Signal::Hold> hold_from(std::string_view word) {
  for (auto h : {Signal::Hold::smooth, Signal::Hold::held, Signal::Hold::linear})
    if (word == to_string(h)) return h;
  return std::nullopt;
}

int highest_derivative_order(const Sum& s) {
  int k = 0;
  walk_factors(s, [&](const Factor& f, const Term&) {
    if (f.kind == FactorKind::derivative) {  // der(y', 2) costs 3: the orders add up
      k = std::max(k, f.order + highest_derivative_order(*f.argument));
      return Step::over;
    }
    if (f.kind == FactorKind::signal || f.kind == FactorKind::initial_value) k = std::max(k, f.order);
    return Step::into;
  });
  return k;
}

std::optional<Number> Sum::as_number() const {
  if (terms.empty()) return Number(0);
  if (terms.size() == 1 && terms[0].is_number()) return terms[0].coefficient;
  return std::nullopt;
}

Term canonical(Term t) {
  auto& f = t.factors;
  std::stable_sort(f.begin(), f.end(), [](const auto& x, const auto& y) { return compare(x.first, y.first) < 0; });
  std::vector<std::pair<Factor, int>> merged;
  for (auto& item : f) {
    if (!merged.empty() && compare(merged.back().first, item.first) == 0) merged.back().second += item.second;
    else merged.push_back(std::move(item));
    // [g]^k = [g]: an indicator is idempotent.
    if (merged.back().first.kind == FactorKind::guard) merged.back().second = 1;
  }
  std::erase_if(merged, [](const auto& x) { return x.second == 0; });
  f = std::move(merged);
  return t;
}

Sum canonical(std::vector<Term> terms) {
  std::stable_sort(terms.begin(), terms.end(), [](const Term& a, const Term& b) { return compare_factors(a, b) < 0; });
  Sum s;
  for (auto& t : terms) {
    if (!s.terms.empty() && compare_factors(s.terms.back(), t) == 0) {
      s.terms.back().coefficient = s.terms.back().coefficient + t.coefficient;
      if (!s.terms.back().span.known()) s.terms.back().span = t.span;
    } else {
      s.terms.push_back(std::move(t));
    }
  }
  std::erase_if(s.terms, [](const Term& t) { return t.coefficient.is_zero(); });
  return s;
}

Sum number(const Number& n, const Span& span) {
  Sum s;
  if (!n.is_zero()) s.terms.push_back(Term{n, {}, span});
  return s;
}

Sum factor(Factor f, int power, const Span& span) {
  Term t{Number(1), {{std::move(f), power}}, span};
  return canonical(std::vector<Term>{canonical(std::move(t))});
}

Sum add(const Sum& a, const Sum& b) {
  std::vector<Term> terms = a.terms;
  terms.insert(terms.end(), b.terms.begin(), b.terms.end());
  return canonical(std::move(terms));
}

Sum negate(const Sum& a) { return scale(a, Number(-1)); }

Sum subtract(const Sum& a, const Sum& b) { return add(a, negate(b)); }

Sum scale(const Sum& a, const Number& k) {
  if (k.is_zero()) return {};
  Sum s = a;
  for (auto& t : s.terms) t.coefficient = t.coefficient * k;
  return s;
}

Term multiply(const Term& a, const Term& b) {
  Term t;
  t.coefficient = a.coefficient * b.coefficient;
  t.factors = a.factors;
  t.factors.insert(t.factors.end(), b.factors.begin(), b.factors.end());
  t.span = a.span.known() ? a.span : b.span;
  return canonical(std::move(t));
}

Sum multiply(const Sum& a, const Sum& b) {
  std::vector<Term> terms;
  terms.reserve(a.terms.size() * b.terms.size());
  for (const auto& x : a.terms)
    for (const auto& y : b.terms) terms.push_back(multiply(x, y));
  return canonical(std::move(terms));
}

SumPtr share(Sum s) { return std::make_shared<const Sum>(std::move(s)); }

const Signal* Model::signal(const std::string& signal_name) const {
  for (const auto& s : signals)
    if (s.name == signal_name) return &s;
  return nullptr;
}

Signal* Model::signal(const std::string& signal_name) {
  return const_cast<Signal*>(static_cast<const Model&>(*this).signal(signal_name));  // one lookup for both
}

int Model::parameter_index(const std::string& parameter_name) const {
  for (std::size_t i = 0; i < parameters.size(); ++i)
    if (parameters[i].name == parameter_name) return static_cast<int>(i);
  return -1;
}

}  // namespace sidc::ir
