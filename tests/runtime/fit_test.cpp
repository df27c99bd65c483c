// Tests of runtime/solve/fit: records, groups, weights and errors, on records where the model's
// equation holds exactly (its input computed from analytic derivatives of the output).
#include <gtest/gtest.h>

#include <cmath>

#include "compiler/pipeline.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {
namespace {

ir::Model compiled(const std::string& text) {
  const auto r = compile(std::make_shared<const SourceFile>("fit_test.sid", text), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return r.ok() ? *r.integrated : ir::Model{};
}

// y = sin(w t + phase) + 0.3 sin(3.1 t); x = a1*y' + a2*y exactly.
SampledRecord first_order_record(double a1, double a2, double phase, std::size_t n = 2001, double h = 1e-3) {
  SampledRecord r;
  r.path = "synthetic";
  r.step = h;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * h;
    const double y = std::sin(2 * t + phase) + 0.3 * std::sin(3.1 * t);
    const double dy = 2 * std::cos(2 * t + phase) + 0.93 * std::cos(3.1 * t);
    r.time.push_back(t);
    r.signals["y"].push_back(y);
    r.signals["x"].push_back(a1 * dy + a2 * y);
  }
  return r;
}

double estimate(const GroupFit& g, const std::string& name) {
  for (const auto& p : g.summary.parameters)
    if (p.name == name) return p.value;
  ADD_FAILURE() << "no parameter " << name;
  return NAN;
}

TEST(Fit, RecoversParametersInDerivativeAndIntegratedForm) {
  for (const char* integrate : {"0", "1"}) {
    const ir::Model m = compiled(std::string("input x\noutput y\nparam a1, a2\nset integrate = ") + integrate + "\na1*y' + a2*y = x\n");
    auto result = fit(m, {first_order_record(0.5, 2.0, 0.3)}, {});
    ASSERT_TRUE(std::holds_alternative<FitSummary>(result)) << render(std::get<Diagnostic>(result));
    const auto& g = std::get<FitSummary>(result).groups.at(0);
    EXPECT_NEAR(estimate(g, "a1"), 0.5, 1e-6) << "integrate " << integrate;
    EXPECT_NEAR(estimate(g, "a2"), 2.0, 1e-6) << "integrate " << integrate;
  }
}

TEST(Fit, EachRecordHasItsOwnIntegrationConstants) {
  const ir::Model m = compiled("input x\noutput y\nparam a1, a2\nset integrate = 1\na1*y' + a2*y = x\n");
  auto result = fit(m, {first_order_record(0.5, 2.0, 0.3), first_order_record(0.5, 2.0, 1.7, 1501)}, {});
  ASSERT_TRUE(std::holds_alternative<FitSummary>(result)) << render(std::get<Diagnostic>(result));
  const auto& g = std::get<FitSummary>(result).groups.at(0);
  EXPECT_EQ(g.columns, (std::vector<std::string>{"a1", "a2", "C1@1", "C1@2"}));
  EXPECT_EQ(g.records.size(), 2u);
  EXPECT_EQ(g.summary.n, g.records[0].rows + g.records[1].rows);
  EXPECT_NEAR(estimate(g, "a1"), 0.5, 1e-6);
  EXPECT_NEAR(estimate(g, "a2"), 2.0, 1e-6);
  // The constants are a1*y(t0) of each record: different phases, different constants.
  EXPECT_GT(std::abs(estimate(g, "C1@1") - estimate(g, "C1@2")), 0.1);
}

TEST(Fit, EquationsSharingNoParameterAreSolvedSeparately) {
  const ir::Model separate = compiled("input x\noutput y\nparam a1, a2, b1\na1*y' + a2*y = x\nb1*y = x - y'\n");
  EXPECT_EQ(equation_groups(separate).size(), 2u);
  const ir::Model joint = compiled("input x\noutput y\nparam a1, a2\na1*y' + a2*y = x\na2*y = x - y'\n");
  EXPECT_EQ(equation_groups(joint).size(), 1u);
}

TEST(Fit, WeightsScaleTheResidualsAsEquation216) {
  const ir::Model m = compiled("input x\noutput y\nparam a1, a2\na1*y' + a2*y = x\n");
  SampledRecord r = first_order_record(0.5, 2.0, 0.3);
  for (std::size_t k = 0; k < r.time.size(); ++k) r.signals["x"].owned()[k] += 0.01 * std::sin(97.0 * static_cast<double>(k));  // noise
  auto plain = fit(m, {r}, {});
  r.weights.assign(r.time.size(), 2.0);
  auto doubled = fit(m, {r}, {});
  ASSERT_TRUE(std::holds_alternative<FitSummary>(plain) && std::holds_alternative<FitSummary>(doubled));
  const auto& p = std::get<FitSummary>(plain).groups.at(0);
  const auto& d = std::get<FitSummary>(doubled).groups.at(0);
  EXPECT_NEAR(d.summary.G, 4 * p.summary.G, 1e-9 * p.summary.G);  // G = sum (w r)^2
  EXPECT_NEAR(estimate(d, "a1"), estimate(p, "a1"), 1e-9);       // uniform weights: same estimates
  EXPECT_TRUE(d.weighted);
  // Zero weight on the first half leaves only the second half's rows.
  for (std::size_t k = 0; k < r.time.size() / 2; ++k) r.weights[k] = 0.0;
  auto half = fit(m, {r}, {});
  ASSERT_TRUE(std::holds_alternative<FitSummary>(half));
  EXPECT_LT(std::get<FitSummary>(half).groups.at(0).summary.n, p.summary.n * 6 / 10);
}

TEST(Fit, AnOperationThatIsNotFiniteIsNamedWithItsSpan) {
  const ir::Model m = compiled("input x\noutput y\nparam a1, a2\na1*log(y) + a2*y = x\n");
  auto result = fit(m, {first_order_record(0.5, 2.0, 0.3)}, {});  // y < 0 somewhere: log is NaN
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(result));
  const Diagnostic& d = std::get<Diagnostic>(result);
  EXPECT_EQ(d.code, "operation-not-finite");
  EXPECT_TRUE(d.span.known());
  EXPECT_NE(d.message.find("log(y)"), std::string::npos) << d.message;
}

}  // namespace
}  // namespace sidc
