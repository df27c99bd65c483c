// Validation of a chaotic system (runtime/simulate/validate.hpp, kRestartPeriods): no free run
// follows a Lorenz record for long, whatever the parameters, because the initial state is known
// only to within the noise and the solution amplifies that error. The sensitivity test (runs from
// the estimated start displaced along its uncertainty's axes) must see that, and the restarted
// runs must then find the true equations to follow; wrong ones must still be said not to; a stable system's
// departure must stay the model's.
//
// How: Lorenz's equations (sigma 10, rho 28, beta 8/3) solved by RK4 at ten steps per sample,
// 0.01 apart over 40 time units, from (-8, 7, 27), noise of 0.1% of each output's standard
// deviation (fixed seed). Measured when written: the free run of the true equations departs at
// about t = 11, a displaced run separates at about the same time, and restarted every 5.5 time
// units they follow at 95-99%; with d (the coefficient of y in y', -1) 2% off the free run
// departs at about t = 5, sooner than half the time a start displaced by the noise takes to
// separate, so the verdict is the free run's.
#include <random>
#include <gtest/gtest.h>

#include "compiler/pipeline.hpp"
#include "runtime/simulate/simulate.hpp"
#include "runtime/simulate/validate.hpp"
#include "support/simulation.hpp"

namespace sidc {
namespace {

const char* kLorenz =
    "output x, y, z\nparam a, b, r, c, d, e, g\n"
    "x' = a*y + b*x\ny' = r*x + c*x*z + d*y\nz' = e*x*y + g*z\n";
const std::vector<double> kTrueLorenz = {10, -10, 28, -1, -1, 1, -8.0 / 3};

struct Compiled {
  CompileResult result;
  ExplicitForm form;
};

Compiled compiled(const char* text) {
  Compiled c{compile(std::make_shared<const SourceFile>("test.sid", text), {}), {}};
  EXPECT_TRUE(c.result.ok()) << c.result.diagnostics.render_all();
  c.form = testing::form_of(*c.result.normalized);
  return c;
}

SampledRecord lorenz_record(const Compiled& c, double share, unsigned seed) {
  SimulateOptions o;
  o.parameters = kTrueLorenz;
  o.initial = {{"x", {-8}}, {"y", {7}}, {"z", {27}}};
  o.time = testing::grid(0, 40, 0.01);
  o.substeps = 10;
  return testing::simulated_record(*c.result.normalized, c.form, o, "lorenz.csv", share, seed);
}

ValidationSummary validated(const Compiled& c, const std::vector<double>& parameters, const SampledRecord& record) {
  ValidationOptions v;
  v.choose_method = true;
  v.check_sensitivity = true;
  auto run = validate(*c.result.normalized, c.form, parameters, record, v);
  EXPECT_TRUE(std::holds_alternative<ValidationSummary>(run)) << render(std::get<Diagnostic>(run));
  return std::get<ValidationSummary>(run);
}

TEST(ChaoticValidation, TheTrueEquationsFollowWithinTheirHorizonThoughTheFreeRunDeparts) {
  const Compiled c = compiled(kLorenz);
  const SampledRecord record = lorenz_record(c, 0.001, 1);
  const ValidationSummary v = validated(c, kTrueLorenz, record);
  // The free run departs: the test is of the path that follows.
  bool departs = false;
  for (const auto& out : v.outputs) departs = departs || (!out.follows && out.departs_at);
  EXPECT_TRUE(departs) << v.statement;
  ASSERT_TRUE(v.restarted.has_value()) << v.statement;
  const auto& r = *v.restarted;
  EXPECT_TRUE(r.sensitive);
  ASSERT_TRUE(r.separates_at.has_value());
  EXPECT_LE(*r.separates_at - r.start, 2 * (r.free_run_departs_at - r.start));
  EXPECT_GT(r.period, 0.3);  // z's oscillation, about 0.75 time units
  EXPECT_LT(r.period, 1.5);
  ASSERT_TRUE(r.judged) << v.statement;
  EXPECT_GE(r.run_duration, kRestartPeriods * r.period);
  EXPECT_GE(r.runs, 3u);
  ASSERT_EQ(r.fit_percent.size(), 3u);
  for (const auto& [output, fit] : r.fit_percent) EXPECT_GT(fit, 92) << output << "\n" << v.statement;
  EXPECT_TRUE(r.follows);
  EXPECT_TRUE(v.follows);
  EXPECT_NE(v.statement.find("follow the record within their horizon of predictability"), std::string::npos) << v.statement;
}

TEST(ChaoticValidation, WrongEquationsDepartSoonerThanTheirSensitivityExplains) {
  const Compiled c = compiled(kLorenz);
  const SampledRecord record = lorenz_record(c, 0.001, 1);
  std::vector<double> wrong = kTrueLorenz;
  wrong[4] *= 1.02;  // d, the -y of y': the free run departs at about t = 5.6, twice as early as a displaced start separates
  const ValidationSummary v = validated(c, wrong, record);
  EXPECT_FALSE(v.follows) << v.statement;
  EXPECT_NE(v.statement.find("do not follow it"), std::string::npos) << v.statement;
  // The departure comes sooner than a start displaced by the record's noise separates (the
  // uncertainty is the noise's, not the misfit's, which a wrong model would widen).
  ASSERT_TRUE(v.restarted.has_value());
  ASSERT_TRUE(v.restarted->separates_at.has_value());  // a chaotic solution: the displaced run separates in the end
  EXPECT_FALSE(v.restarted->sensitive) << v.restarted->free_run_departs_at << " " << *v.restarted->separates_at;
  EXPECT_GT(*v.restarted->separates_at - v.restarted->start, 2 * (v.restarted->free_run_departs_at - v.restarted->start));
}

TEST(ChaoticValidation, AStableSystemsDepartureStaysTheModels) {
  // A damped oscillator with a stiffness 10% high: its free run drifts out of phase, and a start
  // displaced by the estimate's uncertainty is forgotten, so the departure is the model's.
  const Compiled c = compiled("input x = 0.5*cos(1.3*t)\noutput y\nparam a, b, k\na*y'' + b*y' + k*y = x\n");
  SimulateOptions o;
  o.parameters = {1, 0.3, 4};
  o.initial["y"] = {1, 0};
  o.time = testing::grid(0, 40, 0.02);
  o.substeps = 10;
  const SampledRecord record = testing::simulated_record(*c.result.normalized, c.form, o, "oscillator.csv", 0.01, 3);
  const ValidationSummary v = validated(c, {1, 0.05, 4.4}, record);
  EXPECT_FALSE(v.follows) << v.statement;
  ASSERT_FALSE(v.outputs[0].follows);
  if (v.restarted) {
    EXPECT_FALSE(v.restarted->sensitive) << v.statement;
    EXPECT_FALSE(v.restarted->judged);
  }
  EXPECT_EQ(v.statement.find("horizon"), std::string::npos) << v.statement;
}

}  // namespace
}  // namespace sidc
