// The refined instrumental-variable estimate (runtime/solve/instrumental_variables.hpp).
//
// What each check proves:
// - On known-truth records of a forced Duffing oscillator with 1% noise, fitted in the derivative
//   form with a fixed 11-point arc (three seeds), the IV estimate's largest relative parameter
//   error is at least 20 times below the equation-error fit's (measured 80 to 260 times), the
//   iteration converges, every 95% interval holds the truth, and the solved equations follow the
//   record better: the instruments remove the errors-in-variables bias that least squares keeps.
// - Over ten further seeds at least 36 of the 40 intervals hold the truth (measured: 40): the
//   covariance is not too narrow where the rows' residuals are nearly independent.
// - On an exact record IV changes nothing: with no noise the solution is the record, the
//   instruments are the regressors, and the first IV solve is the least-squares one (to rounding).
// - A solution that diverges is said so, naming the record, and the estimate kept is named: when
//   the equation-error estimate's own equations diverge (not started), and when a later iterate's
//   do (stopped; the estimate before it is kept, its values exactly).
#include <gtest/gtest.h>

#include <cstdio>

#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "compiler/pipeline.hpp"
#include "runtime/simulate/simulate.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/solve/instrumental_variables.hpp"
#include "runtime/solve/options_from_settings.hpp"
#include "support/simulation.hpp"

namespace sidc {
namespace {

using testing::form_of;
using testing::grid;

CompileResult compiled(const std::string& text) {
  CompileResult r = compile(std::make_shared<const SourceFile>("iv.sid", text), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return r;
}

// bench/fidelity's Duffing oscillator (docs/accuracy.md): m y'' + c y' + k y + k3 y^3 = x from
// rest, 3000 samples x 0.05, solved by RK4 with 20 steps per sample; Gaussian noise of `share` of
// y's standard deviation.
const char* kDuffingTruth =
    "input x = 1.5*sin(0.7*t) + 0.8*sin(1.9*t + 0.3) + 0.4*sin(3.7*t)\noutput y\nparam m, c, k, k3\nm*y'' + c*y' + k*y + k3*y^3 = x\n";
const std::map<std::string, double> kDuffing{{"m", 1.0}, {"c", 0.25}, {"k", 1.0}, {"k3", 0.5}};

SampledRecord duffing_record(double share, unsigned seed) {
  const CompileResult truth = compiled(kDuffingTruth);
  SimulateOptions o;
  o.parameters = {1.0, 0.25, 1.0, 0.5};
  o.initial["y"] = {0, 0};
  o.time = grid(0, 149.95, 0.05);
  o.substeps = 20;
  auto run = simulate(*truth.normalized, form_of(*truth.normalized), o);
  EXPECT_TRUE(std::holds_alternative<SimulationSummary>(run));
  std::vector<double> y = std::get<SimulationSummary>(run).outputs[0];
  std::mt19937 engine(seed);
  if (share > 0) testing::add_noise(y, share, engine);
  SampledRecord record;
  record.path = "duffing.csv";
  record.step = 0.05;
  record.time = o.time;
  record.signals["y"] = std::move(y);
  for (double t : o.time) record.signals["x"].push_back(1.5 * std::sin(0.7 * t) + 0.8 * std::sin(1.9 * t + 0.3) + 0.4 * std::sin(3.7 * t));
  return record;
}

struct BothFits {
  FitSummary equation_error;
  InstrumentalVariablesSummary iv;
};

// The model's settings as sidc fit reads them (`set derivative`, `set to`, ...).
FitOptions options_of(const CompileResult& c) { return fit_options(evaluation_settings(c.integrated->settings)); }

BothFits fit_both(const CompileResult& c, const std::vector<SampledRecord>& records) {
  const FitOptions options = options_of(c);
  auto fitted = fit(*c.integrated, records, options);
  EXPECT_TRUE(std::holds_alternative<FitSummary>(fitted)) << std::get<Diagnostic>(fitted).message;
  BothFits out{std::get<FitSummary>(std::move(fitted)), {}};
  out.iv = instrumental_variables(*c.integrated, *c.normalized, explicit_form(*c.normalized), records, options, out.equation_error);
  return out;
}

double largest_error(const FitSummary& s, const std::map<std::string, double>& truth) {
  double worst = 0;
  for (const auto& g : s.groups)
    for (const auto& p : g.summary.parameters)
      if (auto t = truth.find(p.name); t != truth.end()) worst = std::max(worst, std::abs(p.value / t->second - 1));
  return worst;
}

double largest_error(const InstrumentalVariablesSummary& s, const std::map<std::string, double>& truth) {
  double worst = 0;
  for (const auto& g : s.groups)
    for (const auto& p : g.parameters)
      if (auto t = truth.find(p.name); t != truth.end()) worst = std::max(worst, std::abs(p.value / t->second - 1));
  return worst;
}

// The derivative form with a fixed 11-point cubic arc (y'' by applying it twice, eq. 3-1.8): the
// regressors y'', y', y, y^3 all carry the noise, and least squares is pulled far off by it (about
// 25% on these records); IV is not.
const char* kDerivativeForm =
    "input x\noutput y\nparam m, c, k, k3\nset form = derivative\nset derivative = savgol(11, 3)\nm*y'' + c*y' + k*y + k3*y^3 = x\n";

TEST(InstrumentalVariables, RemovesTheNoiseBiasOfTheEquationErrorFit) {
  const CompileResult c = compiled(kDerivativeForm);
  for (unsigned seed : {1u, 2u, 3u}) {
    const BothFits f = fit_both(c, {duffing_record(0.01, seed)});
    const double ee = largest_error(f.equation_error, kDuffing), iv = largest_error(f.iv, kDuffing);
    SCOPED_TRACE(::testing::Message() << "seed " << seed << ": equation error " << ee << ", IV " << iv << "; " << f.iv.statement);
    EXPECT_EQ(f.iv.termination, InstrumentalVariablesSummary::Termination::converged);
    EXPECT_TRUE(f.iv.is_solution_usable());
    EXPECT_LE(f.iv.iterations, 10);
    EXPECT_GT(ee, 0.1) << "the equation-error fit is expected far off on this record";
    EXPECT_LT(iv, ee / 20) << "IV is expected to remove the bias (measured: 0.09-0.31% against 23-24%)";
    for (const auto& g : f.iv.groups)
      for (const auto& p : g.parameters)
        if (auto t = kDuffing.find(p.name); t != kDuffing.end()) {
          EXPECT_LE(p.ci_low, t->second) << p.name;
          EXPECT_GE(p.ci_high, t->second) << p.name;
        }
    ASSERT_TRUE(f.iv.fit_percent && f.iv.equation_error_fit_percent);
    EXPECT_GT(*f.iv.fit_percent, *f.iv.equation_error_fit_percent) << "the IV estimate's equations should follow the record better";
  }
}

TEST(InstrumentalVariables, IntervalsHoldTheTruth) {
  const CompileResult c = compiled(kDerivativeForm);
  int held = 0, intervals = 0;
  for (unsigned seed = 4; seed <= 13; ++seed) {
    const BothFits f = fit_both(c, {duffing_record(0.01, seed)});
    EXPECT_EQ(f.iv.termination, InstrumentalVariablesSummary::Termination::converged) << f.iv.statement;
    for (const auto& g : f.iv.groups)
      for (const auto& p : g.parameters)
        if (auto t = kDuffing.find(p.name); t != kDuffing.end()) held += p.ci_low <= t->second && t->second <= p.ci_high, ++intervals;
  }
  EXPECT_EQ(intervals, 40);
  EXPECT_GE(held, 36) << "95% intervals are expected to hold the truth about 95% of the time (measured: 40 of 40)";
}

// Integrated once, every row carries the noise integrated from t0: the IV residuals are a random
// walk, and intervals of independent rows are too narrow. The Newey-West ones allow for it.
TEST(InstrumentalVariables, NeweyWestIntervalsHoldWhereTheRowsAreAutocorrelated) {
  const CompileResult c = compiled(
      "input x\noutput y\nparam m, c, k, k3\nset integrate = 1\nset estimator = iv\nm*y'' + c*y' + k*y + k3*y^3 = x\n");
  int classical = 0, hac = 0, intervals = 0;
  for (unsigned seed = 4; seed <= 13; ++seed) {
    const BothFits f = fit_both(c, {duffing_record(0.01, seed)});
    ASSERT_TRUE(f.iv.is_solution_usable()) << f.iv.statement;
    for (const auto& g : f.iv.groups) {
      ASSERT_TRUE(g.hac) << g.hac_note;
      EXPECT_GT(g.lag1, g.band) << "the integrated rows' residuals are expected autocorrelated";
      for (const auto& p : g.parameters)
        if (auto t = kDuffing.find(p.name); t != kDuffing.end()) {
          classical += p.ci_low <= t->second && t->second <= p.ci_high;
          hac += p.hac_ci_low <= t->second && t->second <= p.hac_ci_high;
          ++intervals;
          EXPECT_GT(p.hac_standard_error, p.standard_error) << p.name;
        }
    }
  }
  EXPECT_EQ(intervals, 40);
  std::printf("integrated IV intervals holding the truth: classical %d, Newey-West %d of %d\n", classical, hac, intervals);
  // Measured: classical 10, Newey-West 35 of 40 (the remaining misses: the integrated rows' bias).
  EXPECT_GE(hac, 34);
  EXPECT_LE(classical, 20);
}

TEST(InstrumentalVariables, ChangesNothingOnAnExactRecord) {
  const CompileResult c = compiled(std::string("input x = 1.5*sin(0.7*t) + 0.8*sin(1.9*t + 0.3) + 0.4*sin(3.7*t)\noutput y\n"
                                               "param m, c, k, k3\nset form = weak\nm*y'' + c*y' + k*y + k3*y^3 = x\n"));
  const BothFits f = fit_both(c, {duffing_record(0.0, 0)});
  EXPECT_EQ(f.iv.termination, InstrumentalVariablesSummary::Termination::converged) << f.iv.statement;
  EXPECT_LE(f.iv.iterations, 2);
  ASSERT_EQ(f.iv.groups.size(), 1u);
  for (const auto& p : f.iv.groups[0].parameters) {
    EXPECT_NEAR(p.value, p.equation_error, 1e-7 * std::abs(p.equation_error)) << p.name;
    EXPECT_NEAR(p.value, kDuffing.at(p.name), 1e-6 * kDuffing.at(p.name)) << p.name;
  }
}

// y' = 0.5 y + x, x = sin t, from y(0) = 0: y = 0.8 e^(t/2) - 0.4 sin t - 0.8 cos t, fitted on
// [0, 10] (`set to`), recorded to t = 60 by a sensor that saturated at its value at t = 10 (119).
// The true equations grow past the divergence bound (1e8 of the record's size: |y| > 1.19e10) near
// t = 47 when solved over the whole record.
const char* kUnstable = "input x = sin(t)\noutput y\nparam a, b\nset integrate = 1\nset to = 10\ny' + a*y = b*x\n";

SampledRecord unstable_record() {
  SampledRecord record;
  record.path = "unstable.csv";
  record.step = 0.02;
  record.time = grid(0, 60, 0.02);
  const auto y = [](double t) { return 0.8 * std::exp(0.5 * t) - 0.4 * std::sin(t) - 0.8 * std::cos(t); };
  for (double t : record.time) {
    record.signals["y"].push_back(y(std::min(t, 10.0)));
    record.signals["x"].push_back(std::sin(t));
  }
  return record;
}

TEST(InstrumentalVariables, SaysWhenTheEquationErrorEstimateDiverges) {
  const CompileResult c = compiled(kUnstable);
  const BothFits f = fit_both(c, {unstable_record()});
  EXPECT_NEAR(largest_error(f.equation_error, {{"a", -0.5}, {"b", 1.0}}), 0.0, 1e-6);
  EXPECT_EQ(f.iv.termination, InstrumentalVariablesSummary::Termination::not_started);
  EXPECT_FALSE(f.iv.is_solution_usable());
  EXPECT_EQ(f.iv.iterations, 0);
  EXPECT_TRUE(f.iv.groups.empty());
  EXPECT_NE(f.iv.statement.find("diverged"), std::string::npos) << f.iv.statement;
  EXPECT_NE(f.iv.statement.find("unstable.csv"), std::string::npos) << f.iv.statement;
  EXPECT_NE(f.iv.statement.find("the equation-error estimate stands"), std::string::npos) << f.iv.statement;
}

TEST(InstrumentalVariables, KeepsTheLastEstimateWhoseEquationsCouldBeSolved) {
  // The same fit with its estimate replaced by a stable one (a = +0.5): its equations solve over the
  // whole record, their solution gives instruments, and on this exact record the first IV solve
  // returns the true, diverging equations; the stable estimate is kept, and said to be.
  const CompileResult c = compiled(kUnstable);
  const std::vector<SampledRecord> records{unstable_record()};
  const FitOptions options = options_of(c);
  auto fitted = fit(*c.integrated, records, options);
  ASSERT_TRUE(std::holds_alternative<FitSummary>(fitted));
  FitSummary stable = std::get<FitSummary>(fitted);
  for (auto& p : stable.groups[0].summary.parameters)
    if (p.name == "a") p.value = 0.5;
  const InstrumentalVariablesSummary iv = instrumental_variables(*c.integrated, *c.normalized, explicit_form(*c.normalized), records, options, stable);
  EXPECT_EQ(iv.termination, InstrumentalVariablesSummary::Termination::stopped) << iv.statement;
  EXPECT_FALSE(iv.is_solution_usable());
  EXPECT_EQ(iv.iterations, 0);
  ASSERT_EQ(iv.changes.size(), 1u);
  EXPECT_NE(iv.statement.find("iteration 1"), std::string::npos) << iv.statement;
  EXPECT_NE(iv.statement.find("diverged"), std::string::npos) << iv.statement;
  EXPECT_NE(iv.statement.find("the equation-error estimate, whose equations could be solved, is kept"), std::string::npos) << iv.statement;
  ASSERT_EQ(iv.groups.size(), 1u);
  for (const auto& p : iv.groups[0].parameters) EXPECT_EQ(p.value, p.equation_error) << p.name;
  EXPECT_EQ(iv.groups[0].parameters[0].value, 0.5);
  EXPECT_NE(iv.full_report().find("Instrumental variables (refined, 0 iterations): stopped"), std::string::npos) << iv.full_report();
}

TEST(InstrumentalVariables, OptionsAreChecked) {
  InstrumentalVariablesOptions o;
  EXPECT_TRUE(o.is_valid(nullptr));
  o.max_iterations = 0;
  std::string why;
  EXPECT_FALSE(o.is_valid(&why));
  EXPECT_NE(why.find("max_iterations"), std::string::npos);
  o = {};
  o.tolerance = -1;
  EXPECT_FALSE(o.is_valid(&why));
  const CompileResult c = compiled(kUnstable);
  const std::vector<SampledRecord> records{unstable_record()};
  auto fitted = fit(*c.integrated, records, options_of(c));
  ASSERT_TRUE(std::holds_alternative<FitSummary>(fitted));
  const auto iv = instrumental_variables(*c.integrated, *c.normalized, explicit_form(*c.normalized), records, options_of(c),
                                         std::get<FitSummary>(fitted), o);
  EXPECT_EQ(iv.termination, InstrumentalVariablesSummary::Termination::not_started);
  EXPECT_NE(iv.statement.find("tolerance"), std::string::npos) << iv.statement;
}

}  // namespace
}  // namespace sidc
