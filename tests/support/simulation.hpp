// Test support for the tests that simulate compiled models in-process (tests/runtime): the
// explicit form of a normalized model, and a uniform time grid.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <variant>
#include <vector>

#include "compiler/explicit_form_pass.hpp"

namespace sidc::testing {

// The model's explicit form; a failure fails the test (and throws bad_variant_access).
inline ExplicitForm form_of(const ir::Model& m) {
  auto f = explicit_form(m);
  EXPECT_TRUE(std::holds_alternative<ExplicitForm>(f)) << render(std::get<Diagnostic>(f));
  return std::get<ExplicitForm>(f);
}

// t0, t0 + step, ..., t1 (the number of steps rounded, so t1 is reached without drift).
inline std::vector<double> grid(double t0, double t1, double step) {
  std::vector<double> t;
  const auto n = static_cast<std::size_t>(std::llround((t1 - t0) / step));
  for (std::size_t i = 0; i <= n; ++i) t.push_back(t0 + static_cast<double>(i) * step);
  return t;
}

}  // namespace sidc::testing
