// runtime/operators/weighted_point_sum: the straight-line program equals, bit for bit, the sum of
// its parts evaluated one PointSum at a time (the simulation's results must not move by a bit),
// for every kind of factor, on ordinary, zero, infinite and NaN values and under frozen modes.
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <gtest/gtest.h>

#include "runtime/operators/point_evaluator.hpp"
#include "runtime/operators/weighted_point_sum.hpp"
#include "support/simulation.hpp"

namespace sidc {
namespace {

using testing::normalized;

bool same_bits(double a, double b) {
  if (std::isnan(a) && std::isnan(b)) return true;
  if (a == 0 && b == 0) return true;  // the sign of a zero sum is not part of the promise
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// The model's first equation, each term a part weighted by its own weight, compiled both ways.
struct Both {
  PointLayout layout;
  std::vector<PointSum> parts;
  std::vector<double> weights;
  WeightedPointSum program;

  Both(const ir::Model& m, const PointCompileOptions& options) {
    std::mt19937 random(7);
    std::uniform_real_distribution<double> weight(-3, 3);
    for (const auto& term : m.equations[0].terms) {
      weights.push_back(weight(random));
      auto c = compile_point_sum(term.operation, layout, options);
      EXPECT_TRUE(std::holds_alternative<PointSum>(c));
      parts.push_back(std::get<PointSum>(std::move(c)));
      EXPECT_FALSE(program.add(weights.back(), static_cast<int>(parts.size()) - 1, term.operation, layout, options));
    }
  }
  double by_parts(const PointInstant& at) const {
    double total = 0;
    for (std::size_t k = 0; k < parts.size(); ++k) total += weights[k] * parts[k].evaluate(at);
    return total;
  }
};

void expect_identical(Both& both, const std::vector<double>& values, double t, std::span<const signed char> modes = {}) {
  std::vector<double> slots(both.layout.size());
  for (std::size_t i = 0; i < slots.size(); ++i) slots[i] = values[i % values.size()];
  const PointInstant at{slots, t, 0.25, modes};
  const double expected = both.by_parts(at), got = both.program.evaluate(at);
  EXPECT_TRUE(same_bits(expected, got)) << expected << " vs " << got;
  for (std::size_t k = 0; k < both.parts.size(); ++k)
    EXPECT_TRUE(same_bits(both.parts[k].evaluate(at), both.program.part_value(k))) << "part " << k;
}

TEST(WeightedPointSum, EqualsThePartsBitForBitOnPolynomialLibraries) {
  // fit_bench's 20-term library: powers 1..7 of y and y' shared between terms.
  const ir::Model m = normalized(
      "input x\noutput y\nparam m, c[1..6], s[1..6], d[1..7]\n"
      "m*y'' + sum(k = 1..6, c[k]*y'^k) + sum(k = 1..6, s[k]*y^k) + sum(k = 1..7, d[k]*y^k*y') = x\n");
  Both both(m, {});
  std::mt19937 random(11);
  std::normal_distribution<double> value(0, 2);
  for (int trial = 0; trial < 2000; ++trial) expect_identical(both, {value(random), value(random), value(random), value(random)}, 0.5);
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  // 0 * inf: PointSum's product keeps a term that has become 0 at 0; a NaN factor makes it NaN.
  // Slots in layout order y'', y', y: y = 0 with y' infinite (and the other way) puts 0 * inf in
  // every y^k * y' term.
  for (const auto& values : std::vector<std::vector<double>>{{1, inf, 0, 1}, {1, 0, inf, 1}, {0, inf, 1, 2}, {inf, 0, 2, 1}, {0, nan, 0, 1},
                                                             {1e200, 1e200, 1e-300, 0}, {-0.0, inf, -inf, 0}, {nan, 1, 1, 1}})
    expect_identical(both, values, 0.5);
  ASSERT_EQ(both.layout.size(), 3u);  // the terms read y'', y', y (x is the known side)
  EXPECT_EQ(both.layout.slots()[2], std::make_pair(std::string("y"), 0));
}

TEST(WeightedPointSum, EqualsThePartsWithFunctionsGuardsPowersAndFrozenModes) {
  const ir::Model m = normalized(
      "input x\noutput y\nparam a[1..9]\n"
      "a[1]*y'' + a[2]*sin(y')*y^2 + a[3]*y'*[y <= 1] + a[4]*y^11 + a[5]*exp(t)*tau + a[6]*(1 + y^2)^0.5 + a[7]*sign(y')*y "
      "+ a[8]*y^(-2)*[y > 0.5]*[y' < 3] + a[9]*abs(y)*y'^2 = x\n");
  const ExplicitForm form = testing::form_of(m);
  PointCompileOptions options;
  options.switching_functions = form.switching_functions;  // guards and sign() read frozen modes
  Both both(m, options);
  std::mt19937 random(13);
  std::normal_distribution<double> value(0.8, 1.5);
  for (int trial = 0; trial < 2000; ++trial) expect_identical(both, {value(random), value(random), value(random)}, value(random));
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& values : std::vector<std::vector<double>>{{2, nan, 1}, {0, 0, 0}, {inf, 1, 1}, {0.5, -inf, 2}, {1, 1, 1}})
    expect_identical(both, values, 0.3);
  // Frozen modes: every combination of the switching functions' signs, and live ones.
  std::vector<signed char> modes(form.switching_functions.size());
  ASSERT_FALSE(modes.empty());
  for (signed char mode : {static_cast<signed char>(-1), static_cast<signed char>(0), static_cast<signed char>(1), kLiveMode}) {
    std::fill(modes.begin(), modes.end(), mode);
    for (int trial = 0; trial < 200; ++trial) expect_identical(both, {value(random), value(random), value(random)}, 0.1, modes);
  }
}

TEST(WeightedPointSum, SaysWhatCannotBeEvaluated) {
  const ir::Model m = normalized("input x\noutput y\nparam a, b\nset integrate = 0\na*y' + b*int(y) = x\n");
  PointLayout layout;
  WeightedPointSum program;
  EXPECT_FALSE(program.add(1.0, 0, m.equations[0].terms[0].operation, layout, {}));
  auto d = program.add(1.0, 1, m.equations[0].terms[1].operation, layout, {});
  ASSERT_TRUE(d);
  EXPECT_EQ(d->code, "simulate-integral");
}

}  // namespace
}  // namespace sidc
