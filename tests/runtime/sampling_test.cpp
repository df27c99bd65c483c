// Uniform-step check, time windows, decimation and resampling, and the thesis' count of usable
// data points (eq. 4-1.10).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "runtime/records/records.hpp"
#include "runtime/records/sampling.hpp"
#include "runtime/operators/savitzky_golay.hpp"

namespace sidc {
namespace {

std::vector<double> uniform_times(std::size_t n, double step, double t0 = 0) {
  std::vector<double> t(n);
  for (std::size_t i = 0; i < n; ++i) t[i] = t0 + static_cast<double>(i) * step;
  return t;
}

Record record_of(const std::string& text) {
  auto result = parse_csv(text, "mem.csv");
  EXPECT_TRUE(std::holds_alternative<Record>(result)) << render(std::get<Diagnostic>(result));
  return std::get<Record>(std::move(result));
}

TEST(UniformStep, FindsTheStep) {
  const auto t = uniform_times(101, 0.01);
  const StepCheck check = check_uniform_step(t);
  ASSERT_TRUE(check.is_uniform());
  EXPECT_NEAR(check.step, 0.01, 1e-16);
}

TEST(UniformStep, ToleratesJitterBelowTheTolerance) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-2e-4, 2e-4);  // in steps, well below 1e-3
  auto t = uniform_times(500, 0.1, 3.0);
  for (double& v : t) v += 0.1 * jitter(rng);
  EXPECT_TRUE(check_uniform_step(t).is_uniform());
  UniformStepOptions strict;
  strict.relative_tolerance = 1e-5;
  EXPECT_EQ(check_uniform_step(t, strict).status, StepCheck::Status::not_uniform);
}

// The median test written out (the check's definition): every spacing within the tolerance of the
// median spacing; otherwise the first that is not. check_uniform_step answers most grids from the
// least and largest spacings alone; it must agree with this everywhere, near the tolerance too.
StepCheck::Status by_the_median(const std::vector<double>& t, double tolerance, std::size_t& bad) {
  std::vector<double> spacing;
  for (std::size_t i = 1; i < t.size(); ++i) spacing.push_back(t[i] - t[i - 1]);
  std::vector<double> sorted = spacing;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const double median = sorted[sorted.size() / 2];
  for (std::size_t i = 0; i < spacing.size(); ++i)
    if (std::fabs(spacing[i] - median) > tolerance * median) {
      bad = i + 1;
      return StepCheck::Status::not_uniform;
    }
  return StepCheck::Status::uniform;
}

TEST(UniformStep, TheQuickAnswerIsTheMediansAnswer) {
  std::mt19937_64 random(11);
  for (int trial = 0; trial < 2000; ++trial) {
    const double step = std::ldexp(1.0, static_cast<int>(random() % 20) - 10) * (1 + 0.1 * static_cast<double>(random() % 7));
    const double tolerance = std::array<double, 3>{1e-3, 1e-6, 0.2}[random() % 3];
    // Jitter from well inside the tolerance to just beyond it, now and then one odd spacing.
    const double jitter = tolerance * step * std::array<double, 5>{0.1, 0.49, 0.5, 0.51, 1.2}[random() % 5];
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<double> t{100.0 * step};
    for (int i = 1; i < 50; ++i) t.push_back(t.back() + step + jitter * u(random));
    if (random() % 4 == 0) t[1 + random() % 48] += 0.9 * tolerance * step * (random() % 2 ? 1 : -1);
    UniformStepOptions options;
    options.relative_tolerance = tolerance;
    const StepCheck check = check_uniform_step(t, options);
    std::size_t bad = 0;
    const auto expected = by_the_median(t, tolerance, bad);
    ASSERT_EQ(check.status, expected) << "trial " << trial;
    if (expected == StepCheck::Status::not_uniform) {
      EXPECT_EQ(check.bad_index, bad) << "trial " << trial;
    }
  }
}

TEST(UniformStep, NamesTheGapNotItsNeighbours) {
  // Ten samples with one missing: the median spacing is the true step, so the gap is the row named.
  std::vector<double> t = {0, 1, 2, 3, 5, 6, 7, 8, 9, 10};
  const StepCheck check = check_uniform_step(t);
  EXPECT_EQ(check.status, StepCheck::Status::not_uniform);
  EXPECT_EQ(check.bad_index, 4u);
  EXPECT_EQ(check.step, 1.0);
}

TEST(UniformStep, RepeatsBackwardsTooFewAndNonFinite) {
  EXPECT_EQ(check_uniform_step(std::vector<double>{0, 1, 1, 2}).status, StepCheck::Status::repeats);
  EXPECT_EQ(check_uniform_step(std::vector<double>{0, 1, 1, 2}).bad_index, 2u);
  EXPECT_EQ(check_uniform_step(std::vector<double>{0, 1, 0.5, 2}).status, StepCheck::Status::goes_backwards);
  EXPECT_EQ(check_uniform_step(std::vector<double>{0, 1, 0.5, 2}).bad_index, 2u);
  EXPECT_EQ(check_uniform_step(std::vector<double>{0}).status, StepCheck::Status::too_few_samples);
  EXPECT_EQ(check_uniform_step(std::vector<double>{0, NAN, 2}).status, StepCheck::Status::not_finite);
}

TEST(UniformStep, RecordDiagnosticNamesTheLine) {
  const Record r = record_of("# c\nt,y\n0,0\n# c\n0.1,1\n0.2,2\n0.35,3\n0.45,4\n");
  auto step = uniform_step(r, "t");
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(step));
  const Diagnostic& d = std::get<Diagnostic>(step);
  EXPECT_EQ(d.code, "data-time-step-not-uniform");
  EXPECT_EQ(d.row, 7);
  EXPECT_EQ(d.column, 1);
  EXPECT_NE(d.hint.find("--resample"), std::string::npos);

  const Record one = record_of("t,y\n0,1\n");
  auto few = uniform_step(one, "t");
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(few));
  EXPECT_EQ(std::get<Diagnostic>(few).code, "data-too-few-samples");

  auto unknown = uniform_step(r, "time");
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(unknown));
  EXPECT_EQ(std::get<Diagnostic>(unknown).code, "data-unknown-column");
}

TEST(TimeWindow, IncludesBoundsDespiteRounding) {
  const auto t = uniform_times(101, 0.01);  // 0 .. 1.0; t[82] is 0.8200000000000001
  const IndexRange w = time_window(t, 0.0, 0.82);
  EXPECT_EQ(w.begin, 0u);
  EXPECT_EQ(w.end, 83u);
  const IndexRange inner = time_window(t, 0.105, 0.2);
  EXPECT_EQ(inner.begin, 11u);
  EXPECT_EQ(inner.end, 21u);
  EXPECT_TRUE(time_window(t, 0.5, 0.4).empty());
  EXPECT_TRUE(time_window(t, 2.0, 3.0).empty());
}

TEST(TimeWindow, EmptyWindowOnARecordIsAnError) {
  const Record r = record_of("t,y\n0,0\n1,1\n2,2\n");
  auto w = time_window(r, "t", 5, 6);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(w));
  EXPECT_EQ(std::get<Diagnostic>(w).code, "data-empty-window");
  auto ok = time_window(r, "t", 0.5, 2);
  ASSERT_TRUE(std::holds_alternative<IndexRange>(ok));
  EXPECT_EQ(std::get<IndexRange>(ok).begin, 1u);
  EXPECT_EQ(std::get<IndexRange>(ok).end, 3u);
}

TEST(Decimate, EveryOtherSampleGivesTheThesisCoarseRecord) {
  const auto fine = uniform_times(101, 0.010);
  const auto coarse = decimate(fine, 2);
  ASSERT_EQ(coarse.size(), 51u);
  for (std::size_t i = 0; i < coarse.size(); ++i) EXPECT_NEAR(coarse[i], 0.020 * static_cast<double>(i), 1e-15);
  EXPECT_EQ(decimate(fine, 3, 1).front(), fine[1]);
  EXPECT_EQ(decimate(fine, 3, 1).size(), 34u);
  EXPECT_TRUE(decimate(fine, 2, 500).empty());
  EXPECT_EQ(decimate(fine, 0).size(), fine.size());
}

// Thesis eq. 4-1.10: n = (0.82 - 3 alpha Delta) / Delta + 1 independent data points, alpha = 2,
// for 7-point cubic operators applied twice (tau0 = 3 alpha Delta lost at the start), on the
// record that runs to t = 1.0 (so the end of the window at 0.82 keeps its neighbourhood).
TEST(ThesisDataPoints, Equation_4_1_10) {
  const DerivativeOptions thesis;  // 7 points, cubic, repeated, drop
  for (const auto& [every, expected] : {std::pair{1, 77}, std::pair{2, 36}}) {
    const auto t = decimate(uniform_times(101, 0.01), static_cast<std::size_t>(every));
    const double delta = 0.01 * every;
    const int lost = samples_lost_each_side(2, thesis);
    EXPECT_EQ(lost, 6);  // tau0 / Delta = 3 alpha
    std::vector<double> y(t.size());
    for (std::size_t i = 0; i < t.size(); ++i) y[i] = std::sin(4 * M_PI * t[i]);
    auto second = estimate_derivative(y, delta, 2, thesis);
    ASSERT_TRUE(std::holds_alternative<std::vector<double>>(second));
    const auto& ydd = std::get<std::vector<double>>(second);
    const IndexRange window = time_window(t, 0.0, 0.82);
    int usable = 0;
    for (std::size_t i = window.begin; i < window.end; ++i) usable += std::isfinite(ydd[i]) ? 1 : 0;
    EXPECT_EQ(usable, expected) << "Delta = " << delta;
    EXPECT_EQ(usable, static_cast<int>(std::lround((0.82 - 3 * 2 * delta) / delta + 1)));
  }
}

TEST(Resample, LinearSignalsAreReproducedExactly) {
  const std::vector<double> t = {0, 0.013, 0.02, 0.031, 0.04, 0.052, 0.06};
  std::vector<double> y(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) y[i] = 3 - 2 * t[i];
  const ResampledSignals out = resample_linear(t, {y}, 0.01);
  ASSERT_EQ(out.time.size(), 7u);
  for (std::size_t k = 0; k < out.time.size(); ++k) {
    EXPECT_NEAR(out.time[k], 0.01 * static_cast<double>(k), 1e-15);
    EXPECT_NEAR(out.columns[0][k], 3 - 2 * out.time[k], 1e-14);
  }
  EXPECT_TRUE(resample_linear(std::vector<double>{0, 1, 1}, {{1, 2, 3}}, 0.5).time.empty());
  EXPECT_TRUE(resample_linear(t, {y}, -1).time.empty());
}

TEST(Resample, RecordRefusesTimeThatGoesBackwardsOrABadStep) {
  const Record backwards = record_of("t,y\n0,0\n2,1\n1,2\n3,3\n");
  auto r = resample_linear(backwards, "t", 1.0);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(r));
  EXPECT_EQ(std::get<Diagnostic>(r).code, "data-time-backwards");
  EXPECT_EQ(std::get<Diagnostic>(r).row, 4);
  const Record fine = record_of("t,y\n0,0\n2,1\n3,3\n");
  auto bad_step = resample_linear(fine, "t", 0.0);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(bad_step));
  EXPECT_EQ(std::get<Diagnostic>(bad_step).code, "data-invalid-resampling-step");
}

TEST(Resample, FaultsKeepTheirLineAfterResampling) {
  // y is empty on line 5 (t = 0.3); the grid point 0.25 lies between lines 4 and 5, 0.3 on line 5.
  const Record r = record_of("# c\nt,y\n0,0\n0.1,1\n0.3,\n0.4,4\n");
  auto resampled = resample_linear(r, "t", 0.05);
  ASSERT_TRUE(std::holds_alternative<Record>(resampled));
  const Record& grid = std::get<Record>(resampled);
  EXPECT_EQ(grid.rows(), 9u);
  EXPECT_EQ((*grid.column("t"))[3], 0.15000000000000002);  // the grid, 0 + 3 * 0.05, not an interpolation
  auto y = complete_column(grid, "y");
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(y));
  EXPECT_EQ(std::get<Diagnostic>(y).code, "data-empty-cell");
  EXPECT_EQ(std::get<Diagnostic>(y).row, 5);
  EXPECT_EQ(std::get<Diagnostic>(y).column, 2);
  // Rows before the fault are plain interpolations.
  EXPECT_NEAR((*grid.column("y"))[1], 0.5, 1e-15);
  EXPECT_EQ(grid.line_of_row(1), 3);
}

}  // namespace
}  // namespace sidc
