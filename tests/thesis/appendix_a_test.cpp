// Thesis Appendix A regenerated (issue 5, item 2): eqs. 4-1.1 and 4-1.2 with the initial
// conditions 4-1.3, solved by sidc's RK4 (examples/thesis-4-1/system_4_1_1.sid), against the
// printed y of Appendix A, row by row.
//
// Relies on: the example model and appendix_a.csv (SIDC_SOURCE_DIR), compiler/explicit_form_pass,
// runtime/simulate/simulate. Guarantees: the check is the brief's, |y_sidc - y_printed| <= 0.005 (half a
// unit of the printed second decimal), at every row but five, and those five are named here and
// bounded by 0.006: the test fails if any other row leaves the half unit, or if one of the five
// comes back inside it (then the finding below is out of date).
//
// The finding (docs/thesis-reproduction.md, "Solving the fitted equation"): at 96 of 101 rows
// the printed y is the correctly rounded solution. At t = 0.11, 0.18, 0.28, 0.34 and 0.77 the
// solution lies within 0.0006 of a rounding boundary (0.9451, 1.7155, 0.9246, -0.5054, 1.0446)
// and the thesis printed the other side: its y was off by about 5e-4 there. Not the step: RK4 at
// Delta = 0.01, 0.005, 0.001 and 0.0001 gives the same five rows to 1e-4 (coarser steps, 0.02,
// make 22 rows miss); not the input (the printed x interpolated, or held over each step, miss
// more rows); not a damper branch chosen once per step (9 to 11 rows). The printed y' shows the
// same thing at the same places (deviations up to 0.036, after each sign change of y'), which
// points at the thesis' arithmetic or at parameters rounded differently than eq. 4-1.2 prints.
#include <cmath>
#include <fstream>
#include <sstream>
#include <gtest/gtest.h>
#include <iostream>
#include <set>

#include "compiler/explicit_form_pass.hpp"
#include "compiler/pipeline.hpp"
#include "runtime/records/records.hpp"
#include "runtime/simulate/simulate.hpp"

#include "support/shell.hpp"

namespace sidc {
namespace {

// The file's text (tests/support/shell.hpp).
std::string read(const std::string& path) { return testing::read_text(path); }

struct Rows {
  std::vector<double> t, y;
};

Rows appendix() {
  auto r = read_csv(std::string(SIDC_SOURCE_DIR "/examples/thesis-4-1/appendix_a.csv"));
  EXPECT_TRUE(std::holds_alternative<Record>(r));
  const Record& record = std::get<Record>(r);
  return {record.column("t")->to_vector(), record.column("y")->to_vector()};
}

SimulationSummary regenerate(int substeps, SimulateOptions::Method method = SimulateOptions::Method::rk4) {
  const std::string path = std::string(SIDC_SOURCE_DIR "/examples/thesis-4-1/system_4_1_1.sid");
  CompileResult c = compile(std::make_shared<const SourceFile>(path, read(path)), {});
  EXPECT_TRUE(c.ok()) << c.diagnostics.render_all();
  auto form = explicit_form(*c.normalized);
  EXPECT_TRUE(std::holds_alternative<ExplicitForm>(form));
  SimulateOptions o;
  const ir::Model& m = *c.normalized;
  // eq. 4-1.2: m = 0.051813, c = 0.5 (y' + 0.005 y'^3) for y' <= 0, y' + 0.010 y'^3 for y' >= 0,
  // k = 30 (y - 0.10 y^2).
  const std::map<std::string, double> values = {{"m", 0.051813}, {"c_minus", 0.5}, {"c3_minus", 0.0025}, {"c_plus", 1.0},
                                                {"c3_plus", 0.010}, {"k", 30.0}, {"k2", -3.0}};
  o.parameters.assign(m.parameters.size(), 0.0);
  for (const auto& [name, v] : values) {
    const int i = m.parameter_index(name);
    EXPECT_GE(i, 0) << name;
    if (i >= 0) o.parameters[static_cast<std::size_t>(i)] = v;
  }
  o.initial["y"] = {0.0, 0.0};  // eq. 4-1.3
  o.time = appendix().t;
  o.substeps = substeps;
  o.method = method;
  o.absolute_tolerance = o.relative_tolerance = 1e-11;
  auto s = simulate(m, std::get<ExplicitForm>(form), o);
  EXPECT_TRUE(std::holds_alternative<SimulationSummary>(s));
  return std::get<SimulationSummary>(s);
}

const std::set<int> kKnownRows = {11, 18, 28, 34, 77};  // t = 0.11, 0.18, 0.28, 0.34, 0.77

void check(const SimulationSummary& s, const std::string& what) {
  ASSERT_TRUE(s.completed()) << s.message;
  const Rows printed = appendix();
  ASSERT_EQ(s.time.size(), printed.y.size());
  std::set<int> outside;
  double worst = 0;
  for (std::size_t i = 0; i < printed.y.size(); ++i) {
    const double d = std::abs(s.outputs[0][i] - printed.y[i]);
    worst = std::max(worst, d);
    if (d > 0.005) outside.insert(static_cast<int>(i));
    EXPECT_LE(d, kKnownRows.count(static_cast<int>(i)) ? 0.006 : 0.005) << what << ": t = " << printed.t[i] << ", sidc y = " << s.outputs[0][i]
                                                                       << ", printed " << printed.y[i];
  }
  EXPECT_EQ(outside, kKnownRows) << what << ": the rows beyond half a unit changed; update the finding";
  std::cout << what << ": max |y_sidc - y_printed| = " << worst << " (" << worst / 0.01 << " units of the last digit), "
            << printed.y.size() - outside.size() << " of " << printed.y.size() << " rows within half a unit\n";
}

TEST(AppendixA, Rk4AtTheRecordStep) { check(regenerate(1), "RK4, Delta = 0.01"); }
TEST(AppendixA, Rk4TenSubsteps) { check(regenerate(10), "RK4, Delta = 0.001"); }
TEST(AppendixA, Adaptive) { check(regenerate(1, SimulateOptions::Method::adaptive), "dopri5, tolerance 1e-11"); }

}  // namespace
}  // namespace sidc
