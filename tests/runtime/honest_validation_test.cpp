// Honest validation (issue 13, item 5): the initial state estimated by least squares over a start
// segment (runtime/simulate/initial_state.hpp), the verdict's fields (follows, departs_at, the
// largest error), centred R^2 beside the uncentred one (runtime/solve/least_squares.hpp), and the
// drift check of integrated forms (runtime/solve/drift_check.hpp).
//
// How: a lightly damped forced oscillator y'' + 0.02 y' + 4 y = 0.5 cos(1.3 t), y(0) = 1, solved
// finely and sampled at 0.02 s over 40 s, with Gaussian noise of 5% of y's standard deviation
// (fixed seed). Its moving-arc y' at the first sample is off by the noise's derivative, and the
// light damping carries that error through the whole record: started there the exact equations
// score below the 90% threshold; started from the estimated state they score close to 100%
// less the noise. Each check can fail: the record-start numbers are asserted below the threshold
// and the estimated ones above, and a wrong stiffness must still be said not to follow.
#include <cmath>
#include <fmt/format.h>
#include <iostream>
#include <numbers>
#include <random>
#include <gtest/gtest.h>

#include "compiler/explicit_form_pass.hpp"
#include "support/simulation.hpp"
#include "compiler/pipeline.hpp"
#include "runtime/simulate/initial_state.hpp"
#include "runtime/simulate/simulate.hpp"
#include "runtime/simulate/validate.hpp"
#include "runtime/solve/drift_check.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/solve/least_squares.hpp"

namespace sidc {
namespace {

CompileResult compiled(const std::string& text) {
  CompileResult r = compile(std::make_shared<const SourceFile>("test.sid", text), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return r;
}

using testing::form_of;
using testing::grid;

const char* kOscillator = "input x = 0.5*cos(1.3*t)\noutput y\nparam a, b, c\na*y'' + b*y' + c*y = x\n";
const std::vector<double> kTrue = {1, 0.02, 4};

// The oscillator's record, noise `share` of y's standard deviation.
SampledRecord noisy_oscillator(const ir::Model& m, const ExplicitForm& f, double share, unsigned seed) {
  SimulateOptions o;
  o.parameters = kTrue;
  o.initial["y"] = {1, 0};
  o.time = grid(0, 40, 0.02);
  o.substeps = 10;
  auto run = simulate(m, f, o);
  EXPECT_TRUE(std::holds_alternative<SimulationSummary>(run));
  std::vector<double> y = std::get<SimulationSummary>(run).outputs[0];
  std::mt19937 engine(seed);
  testing::add_noise(y, share, engine);
  SampledRecord record;
  record.path = "noisy.csv";
  record.step = 0.02;
  record.time = o.time;
  record.signals["y"] = std::move(y);
  return record;
}

ValidationSummary validated(const ir::Model& m, const ExplicitForm& f, const std::vector<double>& parameters, const SampledRecord& record,
                            InitialState initial) {
  ValidationOptions v;
  v.initial_state = initial;
  auto run = validate(m, f, parameters, record, v);
  EXPECT_TRUE(std::holds_alternative<ValidationSummary>(run)) << render(std::get<Diagnostic>(run));
  return std::get<ValidationSummary>(run);
}

TEST(InitialStateEstimate, LiftsANoisyRecordAboveTheThresholdWhereTheRecordedStartFallsBelow) {
  const CompileResult c = compiled(kOscillator);
  const ir::Model& m = *c.normalized;
  const ExplicitForm f = form_of(m);
  for (unsigned seed : {1u, 2u, 3u}) {
    const SampledRecord record = noisy_oscillator(m, f, 0.05, seed);
    const ValidationSummary recorded = validated(m, f, kTrue, record, InitialState::record);
    const ValidationSummary estimated = validated(m, f, kTrue, record, InitialState::estimate);
    std::cout << "seed " << seed << ": fit % from the recorded start " << recorded.outputs[0].fit_percent << " (y' = " << recorded.initial_state[1].second
              << "), from the estimated start " << estimated.outputs[0].fit_percent << " (y' = " << estimated.initial_state[1].second << ", "
              << estimated.estimate_iterations << " steps)\n";
    EXPECT_LT(recorded.outputs[0].fit_percent, kFollowsFitPercent) << seed;
    EXPECT_FALSE(recorded.follows);
    EXPECT_GT(estimated.outputs[0].fit_percent, kFollowsFitPercent) << seed;
    EXPECT_TRUE(estimated.follows);
    EXPECT_TRUE(estimated.outputs[0].follows);
    EXPECT_NE(estimated.statement.find("follow it:"), std::string::npos) << estimated.statement;
    // Both runs start at the same sample; the record's guess is kept beside the estimate.
    EXPECT_EQ(estimated.simulation.time.front(), recorded.simulation.time.front());
    EXPECT_EQ(estimated.recorded_state, recorded.initial_state);
    EXPECT_EQ(estimated.initial_method, InitialState::estimate);
    EXPECT_EQ(estimated.start_segment, start_segment_samples(estimated.simulation.time.size()));
    EXPECT_GT(estimated.estimate_iterations, 0);
    EXPECT_NE(estimated.report("RK4").find("estimated by least squares over the first 199 samples"), std::string::npos)
        << estimated.report("RK4");
  }
}

TEST(InitialStateEstimate, RecoversTheExactStateOfAnExactRecord) {
  const CompileResult c = compiled(kOscillator);
  const ir::Model& m = *c.normalized;
  const ExplicitForm f = form_of(m);
  const SampledRecord record = noisy_oscillator(m, f, 0.0, 1);
  SimulateOptions o;
  o.parameters = kTrue;
  o.time = record.time.to_vector();
  o.substeps = 10;
  o.initial["y"] = {1.1, 0.5};  // a poor guess
  const InitialStateEstimate e = estimate_initial_state(m, f, o, {record.signals.at("y").to_vector()}, 100);
  EXPECT_NEAR(e.initial.at("y")[0], 1.0, 1e-6);
  EXPECT_NEAR(e.initial.at("y")[1], 0.0, 1e-5);
  EXPECT_LT(e.cost_after, 1e-9 * e.cost_before);
}

TEST(Verdict, SaysWhereAWrongModelDepartsAndByHowMuch) {
  const CompileResult c = compiled(kOscillator);
  const ir::Model& m = *c.normalized;
  const ExplicitForm f = form_of(m);
  const SampledRecord record = noisy_oscillator(m, f, 0.01, 4);
  const ValidationSummary good = validated(m, f, kTrue, record, InitialState::estimate);
  EXPECT_TRUE(good.outputs[0].follows);
  EXPECT_FALSE(good.outputs[0].departs_at.has_value()) << *good.outputs[0].departs_at;
  // A stiffness 5% high: the free run drifts out of phase, slowly.
  std::vector<double> stiff = kTrue;
  stiff[2] *= 1.05;
  const ValidationSummary bad = validated(m, f, stiff, record, InitialState::estimate);
  const OutputValidation& y = bad.outputs[0];
  EXPECT_LT(y.fit_percent, kFollowsFitPercent);
  EXPECT_FALSE(y.follows);
  EXPECT_FALSE(bad.follows);
  ASSERT_TRUE(y.departs_at.has_value());
  // It departs early (the start segment cannot fit a wrong frequency either), before its largest error.
  EXPECT_GE(*y.departs_at, bad.simulation.time.front());
  EXPECT_LT(*y.departs_at, y.time_of_max);
  EXPECT_GT(y.max_abs_error, 0.5);
  {  // where it departs, as the definition says: the first local RMS error (11 samples) above a tenth of y's spread
    const Column& recorded = bad.recorded[0];
    std::vector<double> e(recorded.size());
    for (std::size_t i = 0; i < e.size(); ++i) e[i] = recorded[i] - bad.simulation.outputs[0][i];
    double mean = 0, squares = 0;
    for (double v : recorded) mean += v / static_cast<double>(recorded.size());
    for (double v : recorded) squares += (v - mean) * (v - mean);
    const double limit = kDepartureShare * std::sqrt(squares / static_cast<double>(recorded.size()));
    std::optional<double> first;
    for (std::size_t i = 0; i < e.size() && !first; ++i) {
      double sum = 0;
      std::size_t count = 0;
      for (std::size_t k = i >= kDepartureHalfWidth ? i - kDepartureHalfWidth : 0; k <= std::min(e.size() - 1, i + kDepartureHalfWidth); ++k)
        if (std::isfinite(e[k])) sum += e[k] * e[k], ++count;
      if (count && std::sqrt(sum / static_cast<double>(count)) > limit) first = bad.simulation.time[i];
    }
    EXPECT_EQ(first, y.departs_at);
  }
  std::cout << bad.statement << "\n";
  EXPECT_NE(bad.statement.find("do not follow it: fit "), std::string::npos) << bad.statement;
  EXPECT_NE(bad.statement.find(fmt::format("departs at t = {:.4g}", *y.departs_at)), std::string::npos) << bad.statement;
  EXPECT_NE(bad.statement.find(fmt::format("max |E[y]| = {:.4g}", y.max_abs_error)), std::string::npos) << bad.statement;
}

TEST(CentredRSquared, BesideTheUncentredOneOnAKnownDesign) {
  // b = (1, 3, 2, 4) on a = (1, 2, 3, 4), no constant column: x = 29/30, G = 30 - 841/30;
  // uncentred 1 - G/30, centred 1 - G/5 (b's mean is 2.5).
  Eigen::MatrixXd A(4, 1);
  A << 1, 2, 3, 4;
  Eigen::VectorXd b(4);
  b << 1, 3, 2, 4;
  const auto s = solve_least_squares(A, b, {"a"}, nullptr, {});
  const double G = 30 - 841.0 / 30;
  EXPECT_FALSE(s.r_squared_centred);
  EXPECT_NEAR(s.uncentred_r_squared, 1 - G / 30, 1e-14);
  EXPECT_NEAR(s.centred_r_squared, 1 - G / 5, 1e-14);
  EXPECT_EQ(s.r_squared, s.uncentred_r_squared);
  EXPECT_NE(s.full_report().find("R^2 centred (beside it)"), std::string::npos);
  // With a constant column the centred one is r_squared and the uncentred one is beside it.
  Eigen::MatrixXd B(4, 2);
  B << 1, 1, 1, 2, 1, 3, 1, 4;
  const auto t = solve_least_squares(B, b, {"c", "a"}, nullptr, {});
  EXPECT_TRUE(t.r_squared_centred);
  const double H = t.G;
  EXPECT_NEAR(t.centred_r_squared, 1 - H / 5, 1e-14);
  EXPECT_NEAR(t.uncentred_r_squared, 1 - H / 30, 1e-14);
  // A known side that is mostly its mean: uncentred 1.000000, centred far below.
  Eigen::VectorXd level(4);
  level << 1000 + 1, 1000 + 3, 1000 + 2, 1000 + 4;
  Eigen::MatrixXd near_constant(4, 1);
  near_constant << 1000 + 1, 1000 + 2, 1000 + 3, 1000 + 4;
  const auto u = solve_least_squares(near_constant, level, {"a"}, nullptr, {});
  EXPECT_GT(u.uncentred_r_squared, 0.999999);
  EXPECT_LT(u.centred_r_squared, 0.7);
}

TEST(DriftCheck, PolynomialShareSeesTheDegreeKTermBeyondDegreeKMinusOne) {
  const std::vector<double> t = grid(0, 10, 0.01);
  std::vector<double> quadratic, wave, line;
  for (double x : t) {
    quadratic.push_back(3 + 2 * x + 5 * x * x + 0.01 * std::sin(7 * x));
    wave.push_back(std::sin(3 * x) + 2 * x);
    line.push_back(1 + 2 * x);
  }
  EXPECT_GT(polynomial_share(t, quadratic, 2), 0.9999);
  EXPECT_LT(polynomial_share(t, wave, 2), 0.05);   // the line is what the constants absorb
  EXPECT_GT(polynomial_share(t, wave, 1), 0.95);   // once integrated, the line is the drift
  EXPECT_TRUE(std::isnan(polynomial_share(t, line, 2)));  // nothing beyond degree 1 to explain
}

// y'' + 0.3 y' + 2 y = x integrated twice, x defined from y so the equation holds exactly.
std::variant<FitSummary, Diagnostic> fit_twice_integrated(double offset, double duration, CompileResult& c) {
  c = compiled("input x\noutput y\nparam m, c, k\nset integrate = 2\nm*y'' + c*y' + k*y = x\n");
  auto y = [&](double t, int order) {
    const double w1 = 1.3, w2 = 2.1;
    switch (order) {
      case 0: return offset + std::sin(w1 * t) + 0.5 * std::sin(w2 * t + 0.3);
      case 1: return w1 * std::cos(w1 * t) + 0.5 * w2 * std::cos(w2 * t + 0.3);
      default: return -w1 * w1 * std::sin(w1 * t) - 0.5 * w2 * w2 * std::sin(w2 * t + 0.3);
    }
  };
  SampledRecord r;
  r.path = "record.csv";
  r.step = 0.05;
  r.time = grid(0, duration, r.step);
  for (double t : r.time) {
    r.signals["y"].push_back(y(t, 0));
    r.signals["x"].push_back(y(t, 2) + 0.3 * y(t, 1) + 2 * y(t, 0));
  }
  return fit(*c.integrated, {r}, FitOptions{});
}

TEST(DriftCheck, WarnsOnADriftingIntegratedDesignAndNotOnACleanOne) {
  CompileResult c;
  // An output offset of 1 over 200 s: k*int(int(y)) and the known side grow like t^2.
  auto drifting = fit_twice_integrated(1.0, 200, c);
  ASSERT_TRUE(std::holds_alternative<FitSummary>(drifting)) << render(std::get<Diagnostic>(drifting));
  const auto& findings = std::get<FitSummary>(drifting).groups[0].drift;
  ASSERT_FALSE(findings.empty());
  bool known = false;
  for (const auto& f : findings) {
    EXPECT_GT(f.share, kDriftWarningShare);
    EXPECT_EQ(f.degree, 2);
    EXPECT_NE(f.what, "C1");
    known = known || f.what == "known side";
  }
  EXPECT_TRUE(known);
  const auto warnings = drift_warnings(*c.integrated, findings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].severity, Severity::warning);
  EXPECT_EQ(warnings[0].code, "drift-dominates");
  const std::string text = render(warnings[0]);
  std::cout << text << "\n";
  EXPECT_NE(text.find("equation 1 is integrated 2 times and drift dominates it"), std::string::npos) << text;
  EXPECT_NE(text.find("its known side"), std::string::npos) << text;
  EXPECT_NE(text.find("set form = weak"), std::string::npos) << text;
  EXPECT_NE(text.find("set integrate = 1"), std::string::npos) << text;
  // The report shows both R^2 (centred first: the constant C1's column is an intercept).
  const std::string report = std::get<FitSummary>(drifting).full_report(*c.integrated);
  EXPECT_NE(report.find("(centred; uncentred "), std::string::npos) << report;

  // No offset over 20 s: the integrals' drift is the straight line the constants absorb.
  auto clean = fit_twice_integrated(0.0, 20, c);
  ASSERT_TRUE(std::holds_alternative<FitSummary>(clean)) << render(std::get<Diagnostic>(clean));
  EXPECT_TRUE(std::get<FitSummary>(clean).groups[0].drift.empty()) << std::get<FitSummary>(clean).groups[0].drift[0].what << " "
                                                                  << std::get<FitSummary>(clean).groups[0].drift[0].share;
}

TEST(DriftCheck, AConstantTermIntegratedIsAPolynomialByConstructionNotADrift) {
  // a*y' + b*y + d = x integrated once: d's column is tau, exactly; x = y' + 0.5 y + 3.
  const CompileResult c = compiled("input x\noutput y\nparam a, b, d\nset integrate = 1\na*y' + b*y + d = x\n");
  SampledRecord r;
  r.path = "record.csv";
  r.step = 0.05;
  r.time = grid(0, 20, r.step);
  for (double t : r.time) {
    r.signals["y"].push_back(std::sin(1.3 * t));
    r.signals["x"].push_back(1.3 * std::cos(1.3 * t) + 0.5 * std::sin(1.3 * t) + 3);
  }
  auto fitted = fit(*c.integrated, {r}, FitOptions{});
  ASSERT_TRUE(std::holds_alternative<FitSummary>(fitted)) << render(std::get<Diagnostic>(fitted));
  EXPECT_TRUE(std::get<FitSummary>(fitted).groups[0].drift.empty()) << std::get<FitSummary>(fitted).groups[0].drift[0].what;
}

}  // namespace
}  // namespace sidc
