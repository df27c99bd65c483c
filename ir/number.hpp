// Numbers of the compiler: exact rationals while they fit in 64 bits, doubles after that.
//
// The integrator pass divides by powers and factorials (`y^2*y'` -> `y^3/3`, eq. 2-2.7) and the
// thesis' coefficients are decimals (`0.005`); keeping them exact makes rewritten equations print
// exactly and compare exactly (two terms are alike only if their factors are, and their
// coefficients add without round-off). Where an exact result would overflow, or a function such
// as sin() is applied, the number becomes a double and prints in fmt's shortest round-trip form.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace sidc {

class Number {
 public:
  Number() = default;  // exact 0
  Number(std::int64_t n) : num_(n) {}  // NOLINT: integers convert implicitly
  static Number rational(std::int64_t num, std::int64_t den);  // den != 0
  static Number real(double value);                            // inexact
  // Reads a literal as written in a model (`3`, `0.005`, `.5`, `1e-3`): exact when the decimal
  // fits, inexact otherwise. Returns nullopt for text that is not a number.
  static std::optional<Number> parse(std::string_view text);

  bool exact() const { return exact_; }
  std::int64_t numerator() const { return num_; }
  std::int64_t denominator() const { return den_; }
  double value() const;

  bool is_zero() const { return exact_ ? num_ == 0 : real_ == 0.0; }
  bool is_one() const { return exact_ && num_ == 1 && den_ == 1; }
  bool is_integer() const { return exact_ && den_ == 1; }
  bool is_negative() const { return exact_ ? num_ < 0 : real_ < 0.0; }

  Number operator-() const;
  friend Number operator+(const Number& a, const Number& b);
  friend Number operator-(const Number& a, const Number& b) { return a + (-b); }
  friend Number operator*(const Number& a, const Number& b);
  friend Number operator/(const Number& a, const Number& b);  // b != 0
  Number pow(std::int64_t exponent) const;
  Number abs() const { return is_negative() ? -*this : *this; }

  // Total order used for canonical sorting; equal numbers compare equal whatever their form.
  friend int compare(const Number& a, const Number& b);
  friend bool operator==(const Number& a, const Number& b) { return compare(a, b) == 0; }
  friend bool operator<(const Number& a, const Number& b) { return compare(a, b) < 0; }

  // In the language's syntax: `3`, `-0.005` (a decimal when the denominator divides a power of
  // ten, unless it is a small unit fraction such as 1/2), `1/3` otherwise; inexact numbers in shortest round-trip form.
  std::string to_string() const;

 private:
  bool exact_ = true;
  std::int64_t num_ = 0;
  std::int64_t den_ = 1;  // > 0, coprime with num_
  double real_ = 0.0;
};

}  // namespace sidc
