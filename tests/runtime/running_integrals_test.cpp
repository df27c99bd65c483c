// Integrals carried stretch by stretch (runtime/operators/running_integrals.hpp) against the whole
// window prepared at once (block_evaluator.hpp's prepare_whole_window_values): the same values, bit
// for bit, for every stretch length, thread count and rule, nested integrals included; and what
// cannot be carried is said before any work.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "compiler/pipeline.hpp"
#include "runtime/operators/running_integrals.hpp"

namespace sidc {
namespace {

ir::Model compiled(const std::string& text) {
  const auto r = compile(std::make_shared<const SourceFile>("test.sid", text), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return r.ok() ? *r.integrated : ir::Model{};
}

// y = sin(2t + 0.3) + 0.3 sin(3.1t) and an input x, 2001 samples of 1 ms.
SampledRecord record(std::size_t samples = 2001) {
  SampledRecord r;
  r.path = "synthetic";
  r.step = 1e-3;
  for (std::size_t k = 0; k < samples; ++k) {
    const double t = 1e-3 * static_cast<double>(k);
    r.time.push_back(t);
    r.signals["y"].push_back(std::sin(2 * t + 0.3) + 0.3 * std::sin(3.1 * t));
    r.signals["x"].push_back(std::cos(1.3 * t) + 0.1 * t);
  }
  return r;
}

std::vector<const ir::Sum*> sums_of(const ir::Model& m) {
  std::vector<const ir::Sum*> sums;
  for (const auto& e : m.equations) {
    for (const auto& p : e.terms) sums.push_back(&p.operation);
    sums.push_back(&e.known);
  }
  return sums;
}

// Integrated twice: int(int(y'*y)), int(int(sin(y))), int(y), int(int(x)) and the constants' tau.
// (Integer powers are the same repeated products in both evaluators: IntegerPowersToo.)
constexpr const char* kModel =
    "input x\noutput y\nparam a, b, c, d\nset integrate = 2\nset derivative = savgol(7, 3)\n"
    "a*y'' + b*y'*y + c*sin(y) + d*y = x\n";

void expect_carried_equals_whole(const ir::Model& m, const SampledRecord& r, const EvaluationOptions& options, FitWindow w) {
  const auto sums = sums_of(m);
  ASSERT_TRUE(RunningIntegrals::carries(m, options, w, sums));
  auto prepared = prepare_whole_window_values(r, m, options, w, sums);
  ASSERT_TRUE(std::holds_alternative<WholeWindowValues>(prepared));
  const WholeWindowValues& whole = std::get<WholeWindowValues>(prepared);
  ASSERT_GE(whole.integrals.size(), 4u);
  for (const std::size_t stretch : {std::size_t{4}, std::size_t{5}, std::size_t{7}, std::size_t{64}, w.size()}) {
    for (const int threads : {1, 3}) {
      SCOPED_TRACE(::testing::Message() << "stretch " << stretch << ", threads " << threads);
      auto started = RunningIntegrals::start(r, m, options, w, sums);
      ASSERT_TRUE(std::holds_alternative<RunningIntegrals>(started));
      RunningIntegrals running = std::get<RunningIntegrals>(std::move(started));
      for (std::size_t begin = 0; begin < w.size(); begin += stretch) {
        const std::size_t end = std::min(w.size(), begin + stretch);
        ASSERT_FALSE(running.advance(end, threads, 3).has_value());
        ASSERT_EQ(running.values().integrals_first, w.first + begin);
        // Every integral the sums hold; the running ones also carry the integrals nested in them
        // (int(y'*y) inside int(int(y'*y))), which the whole window evaluates on the way.
        for (const auto& [key, expected] : whole.integrals) {
          ASSERT_TRUE(running.values().integrals.count(key)) << key;
          const std::vector<double>& values = running.values().integrals.at(key);
          ASSERT_EQ(values.size(), end - begin) << key;
          for (std::size_t i = 0; i < values.size(); ++i)
            ASSERT_EQ(values[i], expected[w.first + begin + i]) << key << " at window sample " << begin + i;
        }
      }
    }
  }
}

TEST(RunningIntegrals, SimpsonCarriedEqualsTheWholeWindowBitForBit) {
  const ir::Model m = compiled(kModel);
  const SampledRecord r = record();
  EvaluationOptions options;
  options.derivative.window = 7;
  expect_carried_equals_whole(m, r, options, {10, 1990});   // an odd number of samples
  expect_carried_equals_whole(m, r, options, {13, 1990});   // an even number, starting off the record's parity
  expect_carried_equals_whole(m, r, options, {10, 13});     // the shortest window carried
}

TEST(RunningIntegrals, TrapezoidCarriedEqualsTheWholeWindowBitForBit) {
  const ir::Model m = compiled(kModel);
  const SampledRecord r = record();
  EvaluationOptions options;
  options.integration.rule = IntegrationOptions::Rule::trapezoid;
  expect_carried_equals_whole(m, r, options, {10, 1990});
}

TEST(RunningIntegrals, IntegerPowersToo) {
  // y^3 is y^2 * y in both evaluators: the carried integrals are the whole window's, bit for bit.
  const ir::Model m = compiled("input x\noutput y\nparam a, b\nset integrate = 1\na*y' + b*y^3 = x\n");
  const SampledRecord r = record();
  const FitWindow w{5, 1995};
  const auto sums = sums_of(m);
  auto prepared = prepare_whole_window_values(r, m, {}, w, sums);
  ASSERT_TRUE(std::holds_alternative<WholeWindowValues>(prepared));
  auto started = RunningIntegrals::start(r, m, {}, w, sums);
  ASSERT_TRUE(std::holds_alternative<RunningIntegrals>(started));
  RunningIntegrals running = std::get<RunningIntegrals>(std::move(started));
  ASSERT_FALSE(running.advance(w.size(), 2, 16).has_value());
  const auto& whole = std::get<WholeWindowValues>(prepared).integrals;
  ASSERT_FALSE(whole.empty());
  for (const auto& [key, expected] : whole)
    for (std::size_t i = 0; i < w.size(); ++i)
      ASSERT_EQ(running.values().integrals.at(key)[i], expected[w.first + i]) << key << " at window sample " << i;
}

TEST(RunningIntegrals, SaysWhatItCannotCarry) {
  const ir::Model m = compiled(kModel);
  const auto sums = sums_of(m);
  const FitWindow w{10, 1990};
  EXPECT_TRUE(RunningIntegrals::carries(m, {}, w, sums));
  EvaluationOptions smoothed;
  smoothed.integration.smoothing_window = 7;  // the arc reads beyond a stretch
  EXPECT_FALSE(RunningIntegrals::carries(m, smoothed, w, sums));
  EXPECT_FALSE(RunningIntegrals::carries(m, {}, {10, 12}, sums));  // 3 samples: Simpson's first interval reads 4
  const ir::Model derivative_form = compiled("input x\noutput y\nparam a, b\nset integrate = 0\na*y' + b*y = x\n");
  EXPECT_FALSE(RunningIntegrals::carries(derivative_form, {}, w, sums_of(derivative_form)));  // nothing to carry
  const ir::Model held = compiled("input x held\noutput y\nparam a, b\nset integrate = 1\na*y' + b*y = x\n");
  EXPECT_FALSE(RunningIntegrals::carries(held, {}, w, sums_of(held)));  // integrated segment by segment
}

TEST(RunningIntegrals, AdvancingOutOfOrderIsABug) {
  const ir::Model m = compiled(kModel);
  const SampledRecord r = record();
  const FitWindow w{10, 1990};
  auto started = RunningIntegrals::start(r, m, {}, w, sums_of(m));
  ASSERT_TRUE(std::holds_alternative<RunningIntegrals>(started));
  RunningIntegrals running = std::get<RunningIntegrals>(std::move(started));
  EXPECT_THROW(running.advance(3, 1, 8), std::logic_error);  // the first stretch must hold Simpson's first four samples
  ASSERT_FALSE(running.advance(100, 1, 8).has_value());
  EXPECT_THROW(running.advance(50, 1, 8), std::logic_error);
  EXPECT_THROW(running.advance(w.size() + 1, 1, 8), std::logic_error);
}

}  // namespace
}  // namespace sidc
