#include "ir/number.hpp"

#include <charconv>
#include <cmath>
#include <fmt/format.h>
#include <numeric>

namespace sidc {
namespace {

__extension__ typedef __int128 Wide;  // exact products of two 64-bit numbers

std::optional<Number> exact_from_wide(Wide num, Wide den) {
  if (den < 0) num = -num, den = -den;
  Wide a = num < 0 ? -num : num, b = den;
  while (b != 0) {
    const Wide r = a % b;
    a = b;
    b = r;
  }
  if (a > 1) num /= a, den /= a;
  constexpr Wide lo = INT64_MIN + 1, hi = INT64_MAX;
  if (num < lo || num > hi || den > hi) return std::nullopt;
  return Number::rational(static_cast<std::int64_t>(num), static_cast<std::int64_t>(den));
}

}  // namespace

Number Number::rational(std::int64_t num, std::int64_t den) {
  Number n;
  if (den < 0) num = -num, den = -den;
  const std::int64_t g = std::gcd(num, den);
  n.num_ = g > 1 ? num / g : num;
  n.den_ = g > 1 ? den / g : den;
  return n;
}

Number Number::real(double value) {
  Number n;
  n.exact_ = false;
  n.real_ = value;
  return n;
}

std::optional<Number> Number::parse(std::string_view text) {
  // A decimal literal with an optional sign, nothing else: from_chars alone would also read
  // `nan`, `inf` and `infinity`, which are no numbers of the language (`set from = nan`).
  if (text.find_first_not_of("0123456789.eE+-") != std::string_view::npos) return std::nullopt;
  if (!text.empty() && (text[0] == '-' || text[0] == '+')) {
    if (text[0] == '+' || text.size() == 1 || text[1] == '-' || text[1] == '+') return std::nullopt;
    const auto magnitude = parse(text.substr(1));
    if (!magnitude) return std::nullopt;
    return -*magnitude;
  }
  double as_double = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), as_double);
  if (ec != std::errc() || end != text.data() + text.size()) {
    // from_chars does not take a leading '.', which the language allows (`.5`).
    if (!text.empty() && text[0] == '.') {
      std::string with_zero(1, '0');
      with_zero.append(text);
      return parse(with_zero);
    }
    return std::nullopt;
  }
  // Exact reading: digits with an optional point and a decimal exponent.
  Wide mantissa = 0;
  int scale = 0;  // value = mantissa * 10^scale
  std::size_t i = 0;
  bool seen_point = false, overflow = false;
  for (; i < text.size() && (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '.'); ++i) {
    if (text[i] == '.') {
      seen_point = true;
      continue;
    }
    if (mantissa > (Wide(1) << 100)) {
      overflow = true;
      break;
    }
    mantissa = mantissa * 10 + (text[i] - '0');
    if (seen_point) --scale;
  }
  if (!overflow && i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    int exponent = 0;
    const char* first = text.data() + i + 1;
    if (first < text.data() + text.size() && *first == '+') ++first;
    const auto r = std::from_chars(first, text.data() + text.size(), exponent);
    if (r.ec != std::errc() || exponent > 40 || exponent < -40) overflow = true;
    else scale += exponent;
  }
  if (!overflow && scale >= -18 && scale <= 18) {
    Wide num = mantissa, den = 1;
    for (int k = 0; k < scale; ++k) num *= 10;
    for (int k = 0; k < -scale; ++k) den *= 10;
    if (auto exact = exact_from_wide(num, den)) return exact;
  }
  return real(as_double);
}

double Number::value() const { return exact_ ? static_cast<double>(num_) / static_cast<double>(den_) : real_; }

Number Number::operator-() const {
  if (!exact_) return real(-real_);
  if (num_ == INT64_MIN) return real(-value());
  return rational(-num_, den_);
}

Number operator+(const Number& a, const Number& b) {
  if (a.exact_ && b.exact_) {
    if (auto r = exact_from_wide(Wide(a.num_) * b.den_ + Wide(b.num_) * a.den_, Wide(a.den_) * b.den_)) return *r;
  }
  return Number::real(a.value() + b.value());
}

Number operator*(const Number& a, const Number& b) {
  if (a.exact_ && b.exact_) {
    if (auto r = exact_from_wide(Wide(a.num_) * b.num_, Wide(a.den_) * b.den_)) return *r;
  }
  return Number::real(a.value() * b.value());
}

Number operator/(const Number& a, const Number& b) {
  if (a.exact_ && b.exact_ && b.num_ != 0) {
    if (auto r = exact_from_wide(Wide(a.num_) * b.den_, Wide(a.den_) * b.num_)) return *r;
  }
  return Number::real(a.value() / b.value());
}

Number Number::pow(std::int64_t exponent) const {
  if (exponent < 0) return Number(1) / pow(-exponent);
  Number result(1), base = *this;
  for (std::int64_t k = exponent; k > 0; k >>= 1) {  // by squaring; falls back to double on overflow
    if (k & 1) result = result * base;
    if (k > 1) base = base * base;
  }
  return result;
}

int compare(const Number& a, const Number& b) {
  if (a.exact_ && b.exact_) {
    const Wide l = Wide(a.num_) * b.den_, r = Wide(b.num_) * a.den_;
    return l < r ? -1 : (l > r ? 1 : 0);
  }
  const double x = a.value(), y = b.value();
  return x < y ? -1 : (x > y ? 1 : 0);
}

std::string Number::to_string() const {
  if (!exact_) {
    if (std::isnan(real_)) return "nan";
    if (std::isinf(real_)) return real_ < 0 ? "-inf" : "inf";
    std::string s = fmt::format("{}", real_);
    // `1e+20` is not valid in every context a user might paste it to; keep fmt's form but drop '+'.
    if (auto p = s.find("e+"); p != std::string::npos) s.erase(p + 1, 1);
    return s;
  }
  if (den_ == 1) return std::to_string(num_);
  // A denominator 2^a 5^b prints as an exact decimal (0.005), except small unit fractions, which
  // read better as divisions (`t^2/2`, as the thesis writes tau^(m-1)/(m-1)!).
  std::int64_t d = den_;
  int twos = 0, fives = 0;
  while (d % 2 == 0) d /= 2, ++twos;
  while (d % 5 == 0) d /= 5, ++fives;
  if (d == 1 && (den_ >= 10 || (num_ != 1 && num_ != -1))) {
    const int digits = std::max(twos, fives);
    Wide scaled = Wide(num_ < 0 ? -num_ : num_);
    for (int k = 0; k < digits; ++k) scaled *= 10;
    scaled /= den_;
    std::string s;
    for (Wide v = scaled; v > 0 || s.size() < static_cast<std::size_t>(digits) + 1; v /= 10)
      s.insert(s.begin(), static_cast<char>('0' + static_cast<int>(v % 10)));
    s.insert(s.end() - digits, '.');
    return (num_ < 0 ? "-" : "") + s;
  }
  return fmt::format("{}/{}", num_, den_);
}

}  // namespace sidc
