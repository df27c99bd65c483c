// Thesis section 4-2 on a synthetic record: the linear process of eq. 4-2.5, recovered through
// the integrated form of eq. 4-2.4 (integration from the recorded initial values, no fitted
// constants), with measurement noise. The thesis' own record is proprietary. Also the record of the
// same process with its input held between samples (process_held_record.csv): the file and its input.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "compiler/pipeline.hpp"
#include "process_record.hpp"
#include "compiler/explicit_form_pass.hpp"
#include "runtime/simulate/validate.hpp"
#include "runtime/solve/fit.hpp"

#include "support/shell.hpp"

namespace sidc {
namespace {

// The file's text (tests/support/shell.hpp).
std::string read(const std::string& path) { return testing::read_text(path); }

SampledRecord as_sampled(const thesis::ProcessRecord& r) {
  SampledRecord s;
  s.path = "process_record.csv";
  s.step = 0.75;
  s.time = r.t;
  s.signals = {{"x", r.x}, {"y1", r.y1}, {"y2", r.y2}};
  return s;
}

TEST(Section42, TheExampleRecordIsTheGeneratorsOutput) {
  EXPECT_EQ(read(SIDC_SOURCE_DIR "/examples/thesis-4-2/process_record.csv"), thesis::process_record_csv(thesis::process_record()))
      << "regenerate it: build/tests/thesis/write_process_record > examples/thesis-4-2/process_record.csv";
}

TEST(Section42, TheHeldExampleRecordIsTheGeneratorsOutput) {
  EXPECT_EQ(read(SIDC_SOURCE_DIR "/examples/thesis-4-2/process_held_record.csv"),
            thesis::process_record_csv(thesis::process_held_record()))
      << "regenerate it: build/tests/thesis/write_process_record held > examples/thesis-4-2/process_held_record.csv";
}

// The held input is what process_record.hpp says: levels on a 0.1 grid in [70, 130], each held
// for 1 to 4 sample intervals (the last run may be cut by the record's end), and every level
// written exactly to the CSV's 6 decimals.
TEST(Section42, TheHeldInputStepsAtSamplesAndHoldsOneToFourIntervals) {
  const auto r = thesis::process_held_record();
  ASSERT_EQ(r.t.size(), 115u);
  EXPECT_DOUBLE_EQ(r.t.back(), 85.5);
  std::size_t run = 1, changes = 0;
  for (std::size_t k = 0; k < r.x.size(); ++k) {
    EXPECT_GE(r.x[k], 70.0);
    EXPECT_LE(r.x[k], 130.0);
    EXPECT_EQ(r.x[k], std::round(r.x[k] * 10) / 10) << "sample " << k;
    if (k == 0) continue;
    if (r.x[k] == r.x[k - 1]) {
      ++run;
    } else {
      EXPECT_LE(run, 4u) << "a level held for more than 4 intervals before sample " << k;
      run = 1;
      ++changes;
    }
  }
  EXPECT_LE(run, 4u);
  EXPECT_GT(changes, 30u);  // 115 samples at 2.5 intervals per level on average: some 45 levels
}

// The held example's models: eq. 4-2.1 with the input declared held (the form chosen from the data)
// and its twin declaring the same record's input smooth.
TEST(Section42, HeldExampleModelsCompileWithTheirHolds) {
  for (const auto& [file, hold] : {std::pair{"process_held.sid", ir::Signal::Hold::held},
                                   std::pair{"process_held_as_smooth.sid", ir::Signal::Hold::smooth}}) {
    const auto text = read(std::string(SIDC_SOURCE_DIR "/examples/thesis-4-2/") + file);
    const auto compiled = compile(std::make_shared<const SourceFile>(file, text), {});
    ASSERT_TRUE(compiled.ok()) << file << ": " << compiled.diagnostics.render_all();
    const ir::Signal* x = compiled.integrated->signal("x");
    ASSERT_NE(x, nullptr) << file;
    EXPECT_EQ(x->hold, hold) << file;
    EXPECT_TRUE(compiled.integrated->form_from_data) << file << ": the example names no form";
  }
}

TEST(Section42, IntegratedForm424RecoversEquation425) {
  const auto model_text = read(SIDC_SOURCE_DIR "/examples/thesis-4-2/process.sid");
  const auto compiled = compile(std::make_shared<const SourceFile>("process.sid", model_text), {});
  ASSERT_TRUE(compiled.ok()) << compiled.diagnostics.render_all();
  const thesis::ProcessRecord record = thesis::process_record();
  auto result = fit(*compiled.integrated, {as_sampled(record)}, {});
  ASSERT_TRUE(std::holds_alternative<FitSummary>(result)) << render(std::get<Diagnostic>(result));
  const FitSummary& s = std::get<FitSummary>(result);
  ASSERT_EQ(s.groups.size(), 2u);  // the two equations share no parameter: solved separately
  const auto& a = thesis::kProcess;
  const double y2_0 = record.y2.front();
  // a9 = a4 + a2*y2(0) and a10 = a8 + a6*y2(0) (eq. 4-2.3), with the recorded y2(0).
  const std::map<std::string, double> truth{{"a1", a[0]}, {"a2", a[1]}, {"a3", a[2]}, {"a9", a[3] + a[1] * y2_0},
                                            {"a5", a[4]}, {"a6", a[5]}, {"a7", a[6]}, {"a10", a[7] + a[5] * y2_0}};
  // With noise in the outputs, the regressors int(y1), int(y2) carry integrated noise (errors in
  // variables) and, under `constants = initial`, the single noisy sample y(t0) shifts every row's
  // known side: the state coefficients stay within about 1%, the small input coefficient of y2 and
  // the offsets are biased (the thesis, too, found y2 its weak variable). Tolerances say so.
  const std::map<std::string, double> relative{{"a1", 0.03}, {"a2", 0.03}, {"a3", 0.02}, {"a5", 0.03}, {"a6", 0.03}, {"a7", 0.25}};
  for (const auto& g : s.groups) {
    ASSERT_TRUE(g.summary.is_solution_usable()) << g.summary.message;
    EXPECT_EQ(g.summary.n, 115u);  // integrals need no derivative margin: every sample is a row
    for (const auto& p : g.summary.parameters) {
      const double true_value = truth.at(p.name);
      if (auto r = relative.find(p.name); r != relative.end()) {
        EXPECT_LT(std::abs(p.value - true_value), r->second * std::abs(true_value)) << p.name << " = " << p.value << " vs " << true_value;
        if (p.name != "a7") {
          EXPECT_LT(std::abs(p.value - true_value), 3.3 * p.standard_error) << p.name;
        }
      } else {  // offsets a9, a10
        EXPECT_LT(std::abs(p.value - true_value), 0.05) << p.name << " = " << p.value << " vs " << true_value;
      }
    }
  }
}

// Issue 14's target: validation with the true parameters scores better than with any parameter set
// 5% off, once simulation holds the input as the plant did. Declared smooth, the record's steps are
// interpolated by a cubic and the truth itself is visibly off. Scores: the worst output's fit %.
double worst_fit_percent(const std::string& model_file, const SampledRecord& record, const std::vector<double>& parameters) {
  const auto text = read(std::string(SIDC_SOURCE_DIR "/examples/thesis-4-2/") + model_file);
  const auto compiled = compile(std::make_shared<const SourceFile>(model_file, text), {});
  EXPECT_TRUE(compiled.ok()) << compiled.diagnostics.render_all();
  const auto form = explicit_form(*compiled.normalized);
  EXPECT_TRUE(std::holds_alternative<ExplicitForm>(form));
  auto v = validate(*compiled.normalized, std::get<ExplicitForm>(form), parameters, record, ValidationOptions{});
  EXPECT_TRUE(std::holds_alternative<ValidationSummary>(v)) << std::get<Diagnostic>(v).message;
  double worst = 100;
  for (const auto& o : std::get<ValidationSummary>(v).outputs) worst = std::min(worst, o.fit_percent);
  return worst;
}

TEST(Section42, HeldValidationPrefersTheTruthToAnySetFivePercentOff) {
  const std::vector<double> truth(thesis::kProcess.begin(), thesis::kProcess.end());
  for (double noise : {0.0, 0.05}) {
    SampledRecord record = as_sampled(thesis::process_held_record(noise));
    const double true_score = worst_fit_percent("process_held.sid", record, truth);
    for (std::size_t k = 0; k < truth.size(); ++k)
      for (double factor : {0.95, 1.05}) {
        std::vector<double> off = truth;
        off[k] *= factor;
        EXPECT_GT(true_score, worst_fit_percent("process_held.sid", record, off)) << "noise " << noise << ", a" << k + 1 << " x " << factor;
      }
    if (noise == 0.0) {
      EXPECT_GT(true_score, 99.99);
      EXPECT_LT(worst_fit_percent("process_held_as_smooth.sid", record, truth), 99.5);  // measured 99.24
    }
  }
}

}  // namespace
}  // namespace sidc
