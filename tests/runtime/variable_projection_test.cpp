// Nonlinear parameters (`param L = 1.2` inside `sin(L*theta)`, issue 15 item 2) in the runtime:
// variable projection (runtime/solve/variable_projection.hpp) finds the value of least equation
// error from guesses off by factors, never ends worse than its guess, and the output-error
// refinement (runtime/refine/) then estimates every parameter, the nonlinear one with its exact
// sensitivity, reaching from there the minimum it reaches from the truth.
#include <cmath>
#include <random>
#include <gtest/gtest.h>

#include "compiler/pipeline.hpp"
#include "ir/fix_parameters.hpp"
#include "runtime/refine/refine.hpp"
#include "runtime/simulate/simulate.hpp"
#include "runtime/solve/fitted_values.hpp"
#include "runtime/solve/variable_projection.hpp"
#include "support/simulation.hpp"

namespace sidc {
namespace {

using testing::form_of;
using testing::grid;

const char* kPendulum =
    "input u = 2*sin(0.7*t) + 1.5*sin(1.9*t)\noutput theta\nparam J, c, mgl, L = GUESS\n"
    "set form = weak\nJ*theta'' + c*theta' + mgl*sin(L*theta) = u\n";
const std::vector<double> kTruth = {1.0, 0.3, 9.81, 0.8};

CompileResult compiled(double guess) {
  std::string text = kPendulum;
  text.replace(text.find("GUESS"), 5, std::to_string(guess));
  CompileResult r = compile(std::make_shared<const SourceFile>("pendulum.sid", text), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return r;
}

// The pendulum solved finely with the truth from theta = 0.5, every 0.01 s to 40 s, noise of
// `share` of theta's standard deviation.
SampledRecord pendulum_record(const ir::Model& normalized, double share, unsigned seed) {
  SimulateOptions o;
  o.parameters = kTruth;
  o.initial["theta"] = {0.5, 0.0};
  o.time = grid(0, 40, 0.01);
  o.substeps = 8;
  SampledRecord record = testing::simulated_record(normalized, form_of(normalized), o, "pendulum.csv", share, seed);
  std::vector<double> u;  // the input's definition on the grid, as records.cpp fills it in
  for (const double t : record.time) u.push_back(2 * std::sin(0.7 * t) + 1.5 * std::sin(1.9 * t));
  record.signals["u"] = std::move(u);
  return record;
}

VariableProjectionSummary projected(const CompileResult& r, const std::vector<SampledRecord>& records) {
  auto v = variable_projection(*r.integrated, records, {});
  EXPECT_TRUE(std::holds_alternative<VariableProjectionSummary>(v)) << render(std::get<Diagnostic>(v));
  return std::get<VariableProjectionSummary>(v);
}

TEST(VariableProjection, FindsTheNonlinearParameterFromGuessesOffByFactors) {
  const CompileResult at_truth = compiled(0.8);
  const std::vector<SampledRecord> records{pendulum_record(*at_truth.normalized, 0.0, 1)};
  for (const double guess : {0.2, 1.2, 5.0}) {
    const VariableProjectionSummary v = projected(compiled(guess), records);
    ASSERT_EQ(v.names, std::vector<std::string>{"L"});
    EXPECT_NEAR(v.values[0], 0.8, 1e-3) << "guess " << guess << "\n" << v.report();
    EXPECT_LE(v.G_best, v.G_guess);
    EXPECT_LE(v.fits, 120);
    EXPECT_TRUE(v.moved());
    EXPECT_TRUE(std::isnan(v.held[0]) && std::isnan(v.held[2]));
    EXPECT_DOUBLE_EQ(v.held[3], v.values[0]);
  }
  // From the value itself it stays (nothing smaller nearby) and says so.
  const VariableProjectionSummary there = projected(compiled(projected(compiled(1.2), records).values[0]), records);
  EXPECT_NEAR(there.values[0], there.guesses[0], 1e-6 * there.guesses[0]);
}

// sin(L*theta) beside k*theta: as L goes to 0, mgl*sin(L*theta) + k*theta fits theta and theta^3
// ever better with ever larger mgl and k, so G keeps falling; the search stops at its range's edge
// and says the data may not determine L, instead of wandering off to L = 1e-4.
TEST(VariableProjection, NamesAParameterTheDataDoNotDetermine) {
  const CompileResult truth = compiled(0.8);
  const std::vector<SampledRecord> records{pendulum_record(*truth.normalized, 0.02, 1)};  // noise: the exact L would give G = 0
  std::string text = kPendulum;
  text.replace(text.find("GUESS"), 5, "2");
  text.replace(text.find(" = u"), 4, " + k*theta = u");
  text.replace(text.find("param J, c, mgl,"), 16, "param J, c, mgl, k,");
  const CompileResult r = compile(std::make_shared<const SourceFile>("degenerate.sid", text), {});
  ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
  const VariableProjectionSummary v = projected(r, records);
  EXPECT_EQ(v.at_edge, std::vector<std::string>{"L"}) << v.report();
  EXPECT_NEAR(v.values[0], 0.25, 1e-9);
  EXPECT_NE(v.report().find("the data may not determine it"), std::string::npos);
}

const std::vector<double> kDecay = {3.0, 0.5, 0.7};  // a, b, k of y = a*exp(-k*x) + b

CompileResult decay_model(const std::string& guess) {
  CompileResult r = compile(std::make_shared<const SourceFile>("decay.sid", "input x\noutput y\nparam a, b, k = " + guess + "\ny = a*exp(-k*x) + b\n"), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return r;
}

// 60 rows of y = a*exp(-k*x) + b at x = 0, 0.1, ..., with white noise of s.d. `sd` (0: none).
SampledRecord decay_record(double sd, unsigned seed) {
  std::mt19937 engine(seed);
  std::normal_distribution<double> noise(0.0, sd > 0 ? sd : 1.0);
  SampledRecord record;
  record.path = "decay.csv";
  record.step = 1;
  std::vector<double> x, y;
  for (int i = 0; i < 60; ++i) {
    record.time.push_back(i);
    x.push_back(0.1 * i);
    y.push_back(kDecay[0] * std::exp(-kDecay[2] * x.back()) + kDecay[1] + (sd > 0 ? noise(engine) : 0.0));
  }
  record.signals["x"] = std::move(x);
  record.signals["y"] = std::move(y);
  return record;
}

// A static nonlinear regression, y = a*exp(-k*x) + b with white noise: the equation error is the
// output error, so variable projection gives the least-squares estimate, and the intervals of
// nonlinear_intervals (k's from the curvature of G, a's and b's widened by k's uncertainty) must
// hold the truth at about their nominal rate over seeds, and k's standard error match the scatter
// of its estimates.
TEST(VariableProjection, StaticRegressionIntervalsHoldTheTruth) {
  const CompileResult r = decay_model("0.2");
  ASSERT_TRUE(r.ok());
  const std::vector<double>& truth = kDecay;
  const int seeds = 100;
  std::vector<int> held(3, 0);
  std::vector<double> k_estimates, k_errors;
  for (int seed = 0; seed < seeds; ++seed) {
    const std::vector<SampledRecord> records{decay_record(0.05, static_cast<unsigned>(seed))};
    const VariableProjectionSummary v = projected(r, records);
    auto fitted = fit(fix_nonlinear(*r.integrated, v.held), records, {});
    ASSERT_TRUE(std::holds_alternative<FitSummary>(fitted));
    FitSummary& summary = std::get<FitSummary>(fitted);
    const NonlinearIntervals intervals = nonlinear_intervals(*r.integrated, records, {}, v.held, summary);
    ASSERT_EQ(intervals.standard_errors.size(), 1u);
    ASSERT_TRUE(std::isfinite(intervals.standard_errors[0])) << intervals.note;
    for (const auto& e : summary.groups[0].summary.parameters) {
      const std::size_t q = e.name == "a" ? 0 : 1;
      held[q] += e.ci_low <= truth[q] && truth[q] <= e.ci_high;
    }
    held[2] += std::abs(v.values[0] - truth[2]) <= 1.96 * intervals.standard_errors[0];
    k_estimates.push_back(v.values[0]);
    k_errors.push_back(intervals.standard_errors[0]);
  }
  for (std::size_t q = 0; q < 3; ++q) EXPECT_GE(held[q], 86) << "parameter " << q;  // 95% nominal; Wald intervals of a curved model hold a little less
  double mean = 0, squares = 0;
  for (double k : k_estimates) mean += k / seeds;
  for (double k : k_estimates) squares += (k - mean) * (k - mean);
  std::sort(k_errors.begin(), k_errors.end());
  const double ratio = std::sqrt(squares / (seeds - 1)) / k_errors[seeds / 2];
  EXPECT_GT(ratio, 0.8);
  EXPECT_LT(ratio, 1.25);
}

// From a guess of 0 the scan tries both signs, 1/8 to 8 in size: it finds k all the same.
TEST(VariableProjection, FromAGuessOfZero) {
  const CompileResult r = decay_model("0");
  ASSERT_TRUE(r.ok());
  const VariableProjectionSummary v = projected(r, {decay_record(0.0, 0)});
  EXPECT_NEAR(v.values[0], kDecay[2], 1e-6) << v.report();
}

TEST(VariableProjection, ThenRefinementEstimatesEveryParameter) {
  const CompileResult start = compiled(1.2);
  const ir::Model& model = *start.normalized;
  const ExplicitForm form = form_of(model);
  const std::vector<SampledRecord> records{pendulum_record(model, 0.01, 5)};
  const VariableProjectionSummary v = projected(start, records);
  // The equation-error fit at the projected L, then the refinement of all four from there.
  auto linear = fit(fix_nonlinear(*start.integrated, v.held), records, {});
  ASSERT_TRUE(std::holds_alternative<FitSummary>(linear));
  const ir::Model held = fix_nonlinear(model, v.held);
  std::vector<double> from = fitted_parameter_values(held, std::get<FitSummary>(linear), 0.0);
  from.push_back(v.values[0]);  // L is the last parameter
  auto refined = refine(model, form, from, {&records[0]}, {});
  ASSERT_TRUE(std::holds_alternative<RefineSummary>(refined)) << render(std::get<Diagnostic>(refined));
  const RefineSummary& r = std::get<RefineSummary>(refined);
  ASSERT_EQ(r.status, RefineSummary::Status::converged) << r.report();
  ASSERT_EQ(r.parameters.size(), 4u);
  EXPECT_TRUE(r.parameters[3].nonlinear);
  EXPECT_NE(r.report().find("L: entering nonlinearly"), std::string::npos);
  for (std::size_t q = 0; q < kTruth.size(); ++q) {
    EXPECT_NEAR(r.values[q], kTruth[q], 4 * r.parameters[q].standard_error + 1e-9) << r.parameters[q].name << "\n" << r.report();
    EXPECT_LT(std::abs(r.values[q] - kTruth[q]), 0.01 * kTruth[q]) << r.parameters[q].name;
  }
  // The same minimum from the truth: no local minimum stopped it.
  auto from_truth = refine(model, form, kTruth, {&records[0]}, {});
  ASSERT_TRUE(std::holds_alternative<RefineSummary>(from_truth));
  const RefineSummary& t = std::get<RefineSummary>(from_truth);
  EXPECT_NEAR(t.cost_after, r.cost_after, 1e-6 * r.cost_after);
  for (std::size_t q = 0; q < kTruth.size(); ++q) EXPECT_NEAR(t.values[q], r.values[q], 1e-4 * std::abs(kTruth[q]));
}

}  // namespace
}  // namespace sidc
