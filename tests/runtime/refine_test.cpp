// Output-error refinement (runtime/refine/refine.hpp) on records made here with known truth:
// it recovers the parameters from a biased start, reaches the same minimum from the truth (no
// local minimum stopped it), its Gauss-Newton intervals hold the truth at about their nominal
// rate over seeds, several records each get their own initial state, and a start whose
// solution diverges keeps the start and says so.
#include <cmath>
#include <random>
#include <gtest/gtest.h>

#include "compiler/pipeline.hpp"
#include "runtime/refine/refine.hpp"
#include "runtime/simulate/simulate.hpp"
#include "support/simulation.hpp"

namespace sidc {
namespace {

using testing::form_of;
using testing::grid;
using testing::normalized;


// The model solved finely from `initial` with `truth`, sampled every `step` to `end`, Gaussian
// noise of `share` of each output's standard deviation added.
SampledRecord noisy_record(const ir::Model& m, const ExplicitForm& f, const std::vector<double>& truth,
                           std::map<std::string, std::vector<double>> initial, double end, double step, double share, unsigned seed) {
  SimulateOptions o;
  o.parameters = truth;
  o.initial = std::move(initial);
  o.time = grid(0, end, step);
  o.substeps = 20;
  auto run = simulate(m, f, o);
  EXPECT_TRUE(std::holds_alternative<SimulationSummary>(run));
  const SimulationSummary& s = std::get<SimulationSummary>(run);
  EXPECT_TRUE(s.completed()) << s.message;
  SampledRecord record;
  record.path = "record" + std::to_string(seed) + ".csv";
  record.step = step;
  record.time = o.time;
  std::mt19937 engine(seed);
  for (std::size_t j = 0; j < f.outputs.size(); ++j) {
    std::vector<double> y = s.outputs[j];
    testing::add_noise(y, share, engine);
    record.signals[f.outputs[j].name] = std::move(y);
  }
  return record;
}

RefineSummary refined(const ir::Model& m, const ExplicitForm& f, const std::vector<double>& start, const std::vector<const SampledRecord*>& records,
                      int segments = 0) {
  RefineOptions options;
  options.segments = segments;
  auto r = refine(m, f, start, records, options);
  EXPECT_TRUE(std::holds_alternative<RefineSummary>(r)) << render(std::get<Diagnostic>(r));
  return std::get<RefineSummary>(r);
}

double largest_relative_error(const std::vector<double>& values, const std::vector<double>& truth) {
  double worst = 0;
  for (std::size_t q = 0; q < truth.size(); ++q) worst = std::max(worst, std::abs(values[q] - truth[q]) / std::abs(truth[q]));
  return worst;
}

const char* kVanDerPol = "output y\nparam c1, c2, k\ny'' + c1*y' + c2*y^2*y' + k*y = 0\n";

TEST(Refine, VanDerPolFromABiasedStartReachesTheMinimumTheTruthReaches) {
  const ir::Model m = normalized(kVanDerPol);
  const ExplicitForm f = form_of(m);
  const std::vector<double> truth = {-1, 1, 1};
  const SampledRecord record = noisy_record(m, f, truth, {{"y", {2, 0}}}, 40, 0.02, 0.01, 7);
  const std::vector<double> biased = {-0.97, 1.03, 0.99};  // an equation-error fit's kind of bias
  const RefineSummary from_biased = refined(m, f, biased, {&record});
  ASSERT_EQ(from_biased.status, RefineSummary::Status::converged) << from_biased.message;
  EXPECT_LT(from_biased.cost_after, from_biased.cost_before);
  const double error = largest_relative_error(from_biased.values, truth);
  EXPECT_LT(error, 0.1 * largest_relative_error(biased, truth)) << from_biased.report();
  const RefineSummary from_truth = refined(m, f, truth, {&record});
  EXPECT_NEAR(from_truth.cost_after, from_biased.cost_after, 1e-6 * from_biased.cost_after);
  for (std::size_t q = 0; q < truth.size(); ++q) EXPECT_NEAR(from_truth.values[q], from_biased.values[q], 1e-5);
  // The output error is the noise: its weighted cost is about half the number of samples, and white.
  EXPECT_NEAR(from_biased.cost_after / static_cast<double>(from_biased.residuals), 0.5, 0.1);
  EXPECT_TRUE(from_biased.output_error_white) << from_biased.report();
}

// A model without the cubic refined on a Duffing record: the best it can do leaves the cubic's
// effect in the output error, which the whiteness test sees and the report turns into a warning
// about the intervals.
TEST(Refine, AMissingTermLeavesAnOutputErrorThatIsNotWhite) {
  const ir::Model duffing = normalized("input x = cos(1.3*t)\noutput y\nparam m, c, k, k3\nm*y'' + c*y' + k*y + k3*y^3 = x\n");
  const SampledRecord record = noisy_record(duffing, form_of(duffing), {1, 0.25, 1, 0.5}, {{"y", {0.5, 0}}}, 30, 0.05, 0.01, 9);
  const ir::Model linear = normalized("input x = cos(1.3*t)\noutput y\nparam m, c, k\nm*y'' + c*y' + k*y = x\n");
  const RefineSummary r = refined(linear, form_of(linear), {1, 0.25, 1.3}, {&record});
  ASSERT_TRUE(r.improved()) << r.message;
  EXPECT_FALSE(r.output_error_white) << r.report();
  EXPECT_NE(r.report().find("the intervals are too narrow"), std::string::npos);
}

TEST(Refine, IntervalsHoldTheTruthAtAboutTheirNominalRate) {
  const ir::Model m = normalized("input x = cos(1.3*t)\noutput y\nparam m, c, k, k3\nm*y'' + c*y' + k*y + k3*y^3 = x\n");
  const ExplicitForm f = form_of(m);
  const std::vector<double> truth = {1, 0.25, 1, 0.5};
  int held = 0, intervals = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const SampledRecord record = noisy_record(m, f, truth, {{"y", {0.5, 0}}}, 30, 0.05, 0.02, seed);
    std::vector<double> start = truth;
    for (double& v : start) v *= 1.02;
    const RefineSummary r = refined(m, f, start, {&record});
    ASSERT_TRUE(r.improved()) << r.message;
    for (std::size_t q = 0; q < truth.size(); ++q) {
      ASSERT_TRUE(std::isfinite(r.parameters[q].standard_error));
      ++intervals;
      held += std::abs(r.parameters[q].refined - truth[q]) <= 1.96 * r.parameters[q].standard_error;
    }
  }
  // 80 intervals at 95%: fewer than 68 holding would happen by chance with probability < 1e-4.
  EXPECT_GE(held, 68) << held << " of " << intervals;
  EXPECT_LE(held, 80);
}

TEST(Refine, SeveralRecordsShareTheParametersAndKeepTheirOwnStates) {
  const ir::Model m = normalized("input u = sin(0.7*t)\noutput y\nparam a, b, c\ny'' + a*y' + b*y + c*y^3 = u\n");
  const ExplicitForm f = form_of(m);
  const std::vector<double> truth = {0.3, 2, 0.4};
  const SampledRecord first = noisy_record(m, f, truth, {{"y", {1, 0}}}, 20, 0.02, 0.01, 3);
  const SampledRecord second = noisy_record(m, f, truth, {{"y", {-0.5, 1.5}}}, 20, 0.02, 0.01, 4);
  const RefineSummary r = refined(m, f, {0.33, 1.95, 0.45}, {&first, &second});
  ASSERT_TRUE(r.improved()) << r.message;
  ASSERT_EQ(r.records.size(), 2u);
  EXPECT_EQ(r.unknowns, 3u + 2u * 2u);
  EXPECT_LT(largest_relative_error(r.values, truth), 0.01) << r.report();
  // Each record's own initial state, near its truth at its first compared sample.
  EXPECT_GT(r.records[0].initial.at("y")[0], 0.5);
  EXPECT_LT(r.records[1].initial.at("y")[0], 0.0);
}

TEST(Refine, AStartWhoseSolutionDivergesIsKeptAndSaidSo) {
  const ir::Model m = normalized("output y\nparam c, k\ny'' + c*y' + k*y = 0\n");
  const ExplicitForm f = form_of(m);
  const SampledRecord record = noisy_record(m, f, {0.2, 1}, {{"y", {1, 0}}}, 200, 0.05, 0.01, 5);
  const std::vector<double> unstable = {-0.5, 1};  // negative damping: |y| grows past the divergence bound
  const RefineSummary r = refined(m, f, unstable, {&record}, 1);  // single shooting asked for
  EXPECT_EQ(r.status, RefineSummary::Status::failed);
  EXPECT_FALSE(r.improved());
  EXPECT_EQ(r.values, unstable);
  EXPECT_NE(r.message.find("diverged"), std::string::npos) << r.message;
  EXPECT_NE(r.report().find("not refined"), std::string::npos);
}

// The same start by default: its solution diverges at about t = 37 of 200, so the run is cut into
// segments of half that span, each solved from its own initial state, joined by continuity; the
// refinement then starts, and reaches the truth.
TEST(Refine, MultipleShootingRefinesFromAStartWhoseSolutionDiverges) {
  const ir::Model m = normalized("output y\nparam c, k\ny'' + c*y' + k*y = 0\n");
  const ExplicitForm f = form_of(m);
  const std::vector<double> truth = {0.2, 1};
  const SampledRecord record = noisy_record(m, f, truth, {{"y", {1, 0}}}, 200, 0.05, 0.01, 5);
  const RefineSummary r = refined(m, f, {-0.5, 1}, {&record});
  ASSERT_TRUE(r.improved()) << r.message;
  ASSERT_EQ(r.records.size(), 1u);
  EXPECT_GT(r.records[0].segments, 1u);
  EXPECT_NE(r.shooting_reason.find("stop at t ="), std::string::npos) << r.shooting_reason;
  EXPECT_LT(largest_relative_error(r.values, truth), 0.02) << r.report();
  EXPECT_LT(r.largest_defect, 0.1) << "the joined segments are expected continuous to a tenth of the noise";
  EXPECT_NE(r.report().find("multiple shooting"), std::string::npos);
  for (std::size_t q = 0; q < truth.size(); ++q) EXPECT_NEAR(r.values[q], truth[q], 4 * r.parameters[q].standard_error) << r.report();
}

// On a record single shooting handles, segments asked for reach the same minimum: the joins leave
// the solution continuous, so the segments are one run again.
TEST(Refine, SegmentsAskedForReachTheSingleShootingMinimum) {
  const ir::Model m = normalized(kVanDerPol);
  const ExplicitForm f = form_of(m);
  const std::vector<double> truth = {-1, 1, 1};
  const SampledRecord record = noisy_record(m, f, truth, {{"y", {2, 0}}}, 40, 0.02, 0.01, 7);
  const std::vector<double> biased = {-0.97, 1.03, 0.99};
  const RefineSummary single = refined(m, f, biased, {&record}, 1), four = refined(m, f, biased, {&record}, 4);
  ASSERT_TRUE(single.improved() && four.improved()) << single.message << " / " << four.message;
  EXPECT_EQ(four.records[0].segments, 4u);
  for (std::size_t q = 0; q < truth.size(); ++q) {
    EXPECT_NEAR(four.values[q], single.values[q], 0.1 * single.parameters[q].standard_error) << four.report();
    EXPECT_NEAR(four.parameters[q].standard_error, single.parameters[q].standard_error, 0.1 * single.parameters[q].standard_error);
  }
  EXPECT_LT(four.largest_defect, 0.1);
  // More segments than the record holds 20 samples for: one per 20 samples, every one non-empty
  // (an uneven split once left the last one past the record's end).
  for (int asked : {99, 100000}) {
    const RefineSummary many = refined(m, f, biased, {&record}, asked);
    ASSERT_TRUE(many.improved()) << many.message;
    EXPECT_EQ(many.records[0].segments, std::min<std::size_t>(static_cast<std::size_t>(asked), (many.records[0].samples - 1) / 20));
    EXPECT_LT(largest_relative_error(many.values, truth), 0.01) << many.report();
  }
}

}  // namespace
}  // namespace sidc
