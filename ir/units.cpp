#include "ir/units.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <utility>
#include <vector>

namespace sidc::ir {

namespace {

void add_power(Unit& u, const std::string& symbol, const Number& exponent) {
  auto [it, inserted] = u.powers.try_emplace(symbol, exponent);
  if (!inserted) it->second = it->second + exponent;
  if (it->second.is_zero()) u.powers.erase(it);
}

// The SI's coherent derived units with special names, in base units (SI brochure, table 4).
const std::map<std::string, Unit>& derived_units() {
  static const std::map<std::string, Unit> table = [] {
    auto u = [](std::initializer_list<std::pair<const char*, int>> powers) {
      Unit r;
      for (const auto& [s, e] : powers) add_power(r, s, e);
      return r;
    };
    return std::map<std::string, Unit>{
        {"Hz", u({{"s", -1}})},
        {"N", u({{"kg", 1}, {"m", 1}, {"s", -2}})},
        {"Pa", u({{"kg", 1}, {"m", -1}, {"s", -2}})},
        {"J", u({{"kg", 1}, {"m", 2}, {"s", -2}})},
        {"W", u({{"kg", 1}, {"m", 2}, {"s", -3}})},
        {"C", u({{"s", 1}, {"A", 1}})},
        {"V", u({{"kg", 1}, {"m", 2}, {"s", -3}, {"A", -1}})},
        {"F", u({{"kg", -1}, {"m", -2}, {"s", 4}, {"A", 2}})},
        {"Ohm", u({{"kg", 1}, {"m", 2}, {"s", -3}, {"A", -2}})},
        {"S", u({{"kg", -1}, {"m", -2}, {"s", 3}, {"A", 2}})},
        {"Wb", u({{"kg", 1}, {"m", 2}, {"s", -2}, {"A", -1}})},
        {"T", u({{"kg", 1}, {"s", -2}, {"A", -1}})},
        {"H", u({{"kg", 1}, {"m", 2}, {"s", -2}, {"A", -2}})},
        {"rad", Unit{}},
        {"sr", Unit{}},
    };
  }();
  return table;
}

// Printing order: other symbols first, alphabetically (N*m, V/mm), then the SI base units as
// usually written (kg*m^2/s^2).
int rank(const std::string& symbol) {
  static const std::vector<std::string> order{"kg", "m", "s", "A", "K", "mol", "cd"};
  const auto it = std::find(order.begin(), order.end(), symbol);
  return it == order.end() ? -1 : static_cast<int>(it - order.begin());
}

std::string factor_text(const std::string& symbol, const Number& exponent) {
  if (exponent.is_one()) return symbol;
  if (exponent.is_integer()) return symbol + "^" + exponent.to_string();
  return symbol + "^(" + exponent.to_string() + ")";
}

// Recursive descent over `product := factor (('*' | '/') factor)*`,
// `factor := (symbol | '1' | '(' product ')') ['^' exponent]`.
class UnitReader {
 public:
  explicit UnitReader(std::string_view text) : text_(text) {}

  std::optional<Unit> read(UnitParseError* error) {
    auto u = product();
    skip_blanks();
    if (u && at_ < text_.size()) u = fail("`*`, `/` or the end of the unit");
    if (!u && error) *error = error_;
    return u;
  }

 private:
  std::optional<Unit> fail(const std::string& expected) {
    if (error_.message.empty()) error_ = {at_, "expected " + expected};
    return std::nullopt;
  }
  void skip_blanks() {
    while (at_ < text_.size() && (text_[at_] == ' ' || text_[at_] == '\t')) ++at_;
  }
  bool eat(char c) {
    skip_blanks();
    if (at_ < text_.size() && text_[at_] == c) return ++at_, true;
    return false;
  }
  static bool symbol_char(char c, bool first) {
    const auto u = static_cast<unsigned char>(c);
    return std::isalpha(u) || c == '_' || c == '%' || u >= 0x80 || (!first && std::isdigit(u));
  }

  std::optional<Unit> product() {
    auto u = factor();
    while (u) {
      if (eat('*')) {
        auto f = factor();
        if (!f) return std::nullopt;
        u = multiply(*u, *f);
      } else if (eat('/')) {
        auto f = factor();
        if (!f) return std::nullopt;
        u = divide(*u, *f);
      } else {
        break;
      }
    }
    return u;
  }

  std::optional<Unit> factor() {
    skip_blanks();
    std::optional<Unit> base;
    if (eat('(')) {
      base = product();
      if (!base) return std::nullopt;
      if (!eat(')')) return fail("`)`");
    } else if (at_ < text_.size() && text_[at_] == '1' &&
               (at_ + 1 == text_.size() || !std::isdigit(static_cast<unsigned char>(text_[at_ + 1])))) {
      ++at_;
      base = Unit{};
    } else if (at_ < text_.size() && symbol_char(text_[at_], true)) {
      const std::size_t start = at_;
      while (at_ < text_.size() && symbol_char(text_[at_], at_ == start)) ++at_;
      base = Unit{};
      add_power(*base, std::string(text_.substr(start, at_ - start)), 1);
    } else {
      return fail("a unit such as `m`, `kg`, `N` or `1`");
    }
    if (!eat('^')) return base;
    auto e = exponent();
    if (!e) return std::nullopt;
    return power(*base, *e);
  }

  // `2`, `-2`, `(1/2)`, `(-3/2)`.
  std::optional<Number> exponent() {
    const bool parenthesised = eat('(');
    skip_blanks();
    const bool negative = at_ < text_.size() && text_[at_] == '-';
    if (negative) ++at_;
    auto whole = [&]() -> std::optional<std::int64_t> {
      skip_blanks();
      const std::size_t start = at_;
      std::int64_t v = 0;
      while (at_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[at_])) && at_ - start < 3)
        v = 10 * v + (text_[at_++] - '0');
      if (at_ == start) return std::nullopt;
      return v;
    };
    auto numerator = whole();
    if (!numerator) return fail("a whole exponent of at most three digits, e.g. `2`, `-1` or `(1/2)`"), std::nullopt;
    std::int64_t denominator = 1;
    if (parenthesised && eat('/')) {
      auto d = whole();
      if (!d || *d == 0) return fail("a non-zero denominator"), std::nullopt;
      denominator = *d;
    }
    if (parenthesised && !eat(')')) return fail("`)`"), std::nullopt;
    return Number::rational(negative ? -*numerator : *numerator, denominator);
  }

  std::string_view text_;
  std::size_t at_ = 0;
  UnitParseError error_;
};

}  // namespace

Unit multiply(const Unit& a, const Unit& b) {
  Unit r = a;
  for (const auto& [s, e] : b.powers) add_power(r, s, e);
  return r;
}

Unit divide(const Unit& a, const Unit& b) { return multiply(a, power(b, Number(-1))); }

Unit power(const Unit& u, const Number& exponent) {
  Unit r;
  for (const auto& [s, e] : u.powers) add_power(r, s, e * exponent);
  return r;
}

Unit in_base_units(const Unit& u) {
  Unit r;
  for (const auto& [s, e] : u.powers) {
    const auto it = derived_units().find(s);
    if (it == derived_units().end())
      add_power(r, s, e);
    else
      r = multiply(r, power(it->second, e));
  }
  return r;
}

bool same_dimension(const Unit& a, const Unit& b) { return in_base_units(divide(a, b)).is_one(); }

std::string to_string(const Unit& u) {
  std::vector<std::pair<std::string, Number>> up, down;
  for (const auto& [s, e] : u.powers) (e.is_negative() ? down : up).emplace_back(s, e.abs());
  auto by_rank = [](const auto& a, const auto& b) {
    return rank(a.first) != rank(b.first) ? rank(a.first) < rank(b.first) : a.first < b.first;
  };
  std::sort(up.begin(), up.end(), by_rank);
  std::sort(down.begin(), down.end(), by_rank);
  auto join = [](const auto& factors) {
    std::string s;
    for (const auto& [symbol, exponent] : factors) s += (s.empty() ? "" : "*") + factor_text(symbol, exponent);
    return s;
  };
  std::string text = up.empty() ? "1" : join(up);
  if (!down.empty()) text += "/" + (down.size() > 1 ? "(" + join(down) + ")" : join(down));
  return text;
}

Unit simplest(const Unit& u) {
  // rad and sr stay visible (a torsional stiffness in N*m/rad says what it turns), so the base
  // form keeps them too; it wins only with fewer symbols.
  Unit base = in_base_units(u);
  for (const char* kept : {"rad", "sr"})
    if (auto it = u.powers.find(kept); it != u.powers.end()) add_power(base, kept, it->second);
  return base.powers.size() < u.powers.size() ? base : u;
}

std::optional<Unit> parse_unit(std::string_view text, UnitParseError* error) { return UnitReader(text).read(error); }

}  // namespace sidc::ir
