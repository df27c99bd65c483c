// Units of measurement: products of named units with rational exponents (`kg*m^2/s^2`).
//
// A model may give its signals units (`output theta [rad]`, `input u [N*m]`) and its time one
// (`set time_unit = s`); compiler/unit_pass.cpp then derives every parameter's unit from its term
// and the equation's parameter-free side. Units are symbols, not scales: `mm` is not 0.001 `m`
// (sidc converts no data), so two units agree only when they are the same product of symbols once
// the SI's coherent derived units are written in base units (N = kg*m/s^2, V = kg*m^2/(s^3*A),
// ...) and the radian and steradian, which the SI counts as 1, are left out.
//
// Relies on: ir/number.hpp for exact exponents. Guarantees: every operation returns a unit in
// canonical form (exponents merged, none zero), so equal products compare equal.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "ir/number.hpp"

namespace sidc::ir {

struct Unit {
  std::map<std::string, Number> powers;  // symbol -> exponent, none zero

  bool is_one() const { return powers.empty(); }
};

Unit multiply(const Unit& a, const Unit& b);
Unit divide(const Unit& a, const Unit& b);
Unit power(const Unit& u, const Number& exponent);

// The same unit in SI base units (kg, m, s, A, K, mol, cd) where its symbols are coherent derived
// ones, without rad and sr; other symbols stay as they are.
Unit in_base_units(const Unit& u);

// Whether two units measure the same quantity in the same scale (see the file comment).
bool same_dimension(const Unit& a, const Unit& b);
// Dimensionless: 1, rad or sr, or a product of them.
inline bool is_dimensionless(const Unit& u) { return in_base_units(u).is_one(); }

// As a user writes it: `kg*m^2/s^2`, `1/s`, `m^(1/2)`, `1` for no unit.
std::string to_string(const Unit& u);

// The shorter of `u` and its base-unit form (N*s^2/m reads better as kg; V/mm does not as
// kg*m^2/(s^3*A*mm)): what a report prints for a derived unit.
Unit simplest(const Unit& u);

// Reads `kg*m^2/s^2`, `N*m`, `1/s`, `m/(s*K)`, `1`: symbols of letters (and `%`), `*`, `/`, `^`
// with a whole or parenthesised fraction exponent, parentheses. On error: nullopt, with the
// byte offset within `text` and what was expected there.
struct UnitParseError {
  std::size_t offset = 0;
  std::string message;
};
std::optional<Unit> parse_unit(std::string_view text, UnitParseError* error = nullptr);

}  // namespace sidc::ir
