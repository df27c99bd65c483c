// runtime/solve/residual_correlation: white noise stays inside the 99% band at about the expected rate,
// AR(1) residuals and a delayed input effect are detected at the right lags, records are never
// correlated across their join, and short, constant or non-finite input comes back as a status.
// Which intervals to trust: the classical ones for white residuals unless the fit's Newey-West ones
// are more than twice as wide (kHacWideningToTrust), Newey-West's for autocorrelated residuals.
//
// Relies on: std::mt19937 with fixed seeds (deterministic with one standard library).
#include "runtime/solve/residual_correlation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include <gtest/gtest.h>

namespace sidc {
namespace {

std::vector<double> white_noise(std::size_t n, unsigned seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> normal(0, 1);
  std::vector<double> out(n);
  for (auto& v : out) v = normal(generator);
  return out;
}

// e[t] = phi e[t-1] + white noise (phi = 1: a random walk).
std::vector<double> autoregressive(double phi, std::size_t n, unsigned seed) {
  std::vector<double> e = white_noise(n, seed);
  for (std::size_t t = 1; t < e.size(); ++t) e[t] += phi * e[t - 1];
  return e;
}

double value_at(const CorrelationCurve& curve, int lag) {
  for (std::size_t i = 0; i < curve.lags.size(); ++i)
    if (curve.lags[i] == lag) return curve.values[i];
  ADD_FAILURE() << "lag " << lag << " not in curve";
  return NAN;
}

TEST(ResidualCorrelation, WhiteNoiseStaysInsideTheBandAtTheExpectedRate) {
  const int records = 60;
  const std::size_t n = 1000;
  int outside = 0, lags_tested = 0, judged_white = 0;
  for (int seed = 1; seed <= records; ++seed) {
    const auto summary = residual_correlation({white_noise(n, static_cast<unsigned>(seed))}, {}, {});
    ASSERT_TRUE(summary.is_usable()) << summary.message;
    EXPECT_EQ(summary.max_lag, 25);  // min(25, N/4)
    EXPECT_NEAR(summary.band, 2.5758293035489 / std::sqrt(1000.0), 1e-12);
    EXPECT_DOUBLE_EQ(summary.autocorrelation.values[0], 1.0);
    outside += static_cast<int>(summary.autocorrelation.lags_outside.size());
    lags_tested += summary.max_lag;
    judged_white += summary.residuals_white ? 1 : 0;
  }
  std::printf("white noise, %d records of %zu: %d of %d lags outside the 99%% band, %d records judged white\n", records,
              n, outside, lags_tested, judged_white);
  // 1500 lags at 1% each: 15 expected; the binomial 99.9% range is about [4, 29].
  EXPECT_GE(outside, 4);
  EXPECT_LE(outside, 29) << "lags outside: " << outside << " of " << lags_tested;
  // The verdict's false-alarm rate is about 2% (binomial count 1% + one lag beyond Bonferroni 1%).
  EXPECT_GE(judged_white, records - 5);
}

TEST(ResidualCorrelation, Ar1ResidualsAreDetectedAtLagOne) {
  const auto e = autoregressive(0.5, 1000, 7);
  const auto summary = residual_correlation({e}, {}, {});
  ASSERT_TRUE(summary.is_usable()) << summary.message;
  EXPECT_FALSE(summary.residuals_white);
  EXPECT_FALSE(summary.autocorrelation.white);
  EXPECT_NEAR(value_at(summary.autocorrelation, 1), 0.5, 0.1);
  EXPECT_NEAR(value_at(summary.autocorrelation, 2), 0.25, 0.1);
  ASSERT_FALSE(summary.autocorrelation.lags_outside.empty());
  EXPECT_EQ(summary.autocorrelation.lags_outside.front(), 1);
  EXPECT_NE(summary.verdict.find("autocorrelated at lags 1"), std::string::npos) << summary.verdict;
}

TEST(ResidualCorrelation, SaysWhichIntervalsToTrust) {
  const auto white = residual_correlation({white_noise(1000, 11)}, {}, {});
  ASSERT_TRUE(white.is_usable() && white.autocorrelation.white) << white.message;
  const double none = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(trust_newey_west(white, none));
  EXPECT_FALSE(trust_newey_west(white, 1.5));
  EXPECT_FALSE(trust_newey_west(white, kHacWideningToTrust));
  EXPECT_TRUE(trust_newey_west(white, 3.0));
  EXPECT_NE(white.brief_report(none).find("the residuals do not contradict it"), std::string::npos);
  EXPECT_NE(white.brief_report(1.5).find("the residuals do not contradict it"), std::string::npos);
  const std::string wide = white.brief_report(3.0);
  EXPECT_NE(wide.find("the residuals look white, but the Newey-West (HAC) ones are up to 3 times as wide"), std::string::npos) << wide;
  EXPECT_NE(wide.find("trust the Newey-West ones"), std::string::npos) << wide;
  const auto e = autoregressive(0.5, 1000, 7);
  const auto correlated = residual_correlation({e}, {}, {});
  ASSERT_TRUE(correlated.is_usable()) << correlated.message;
  EXPECT_TRUE(trust_newey_west(correlated, none));
  EXPECT_NE(correlated.brief_report(none).find("are too narrow here; trust the Newey-West"), std::string::npos);
}

TEST(ResidualCorrelation, LongRunsOfLagsAreListedAsRanges) {
  // A random walk's residuals: every lag 1..25 outside the band, written as one range.
  const auto e = autoregressive(1.0, 1000, 9);
  const auto summary = residual_correlation({e}, {}, {});
  ASSERT_TRUE(summary.is_usable());
  EXPECT_EQ(summary.autocorrelation.lags_outside.size(), 25u);
  EXPECT_EQ(summary.autocorrelation.verdict, "correlated at lags 1 to 25");
}

TEST(ResidualCorrelation, WeakAr1IsCaughtByTheWidenedBandAlone) {
  // phi = 0.3 puts only lags 1 and 2 outside the band (not more than chance allows over 25 lags),
  // but lag 1 (0.3) lies far beyond the Bonferroni band (about 3.5/sqrt(N) = 0.11).
  const auto e = autoregressive(0.3, 1000, 11);
  const auto summary = residual_correlation({e}, {}, {});
  ASSERT_TRUE(summary.is_usable());
  EXPECT_GT(summary.bonferroni_band, summary.band);
  EXPECT_FALSE(summary.residuals_white) << summary.verdict;
}

TEST(ResidualCorrelation, DelayedInputEffectIsFoundAtItsLag) {
  const std::size_t n = 2000;
  const auto u = white_noise(n, 21);
  const auto noise = white_noise(n, 22);
  std::vector<double> e(n);
  for (std::size_t t = 0; t < n; ++t) e[t] = noise[t] + (t >= 3 ? 0.6 * u[t - 3] : 0.0);  // e(t) = 0.6 u(t-3) + w
  const auto summary = residual_correlation({e}, {{"x", {u}}}, {});
  ASSERT_TRUE(summary.is_usable()) << summary.message;
  ASSERT_EQ(summary.cross.size(), 1u);
  const auto& cross = summary.cross[0];
  ASSERT_TRUE(cross.computed);
  EXPECT_EQ(cross.lags.front(), -summary.max_lag);
  EXPECT_EQ(cross.lags.back(), summary.max_lag);
  // The largest |r| is at lag +3 (the input three samples earlier), about 0.6 / sqrt(1 + 0.36).
  const auto peak = std::max_element(cross.values.begin(), cross.values.end(),
                                     [](double a, double b) { return std::fabs(a) < std::fabs(b); });
  EXPECT_EQ(cross.lags[static_cast<std::size_t>(peak - cross.values.begin())], 3);
  EXPECT_NEAR(*peak, 0.6 / std::sqrt(1.36), 0.05);
  EXPECT_FALSE(cross.white);
  EXPECT_NE(summary.verdict.find("correlated with `x` at lags 3"), std::string::npos) << summary.verdict;
  // The autocorrelation of e itself is white (u is white): only the cross-correlation flags it.
  EXPECT_TRUE(summary.autocorrelation.white) << summary.autocorrelation.verdict;
}

TEST(ResidualCorrelation, SegmentsAreNeverCorrelatedAcrossTheirJoin) {
  // By hand: A = {1,2,3,4} -> centred {-1.5,-0.5,0.5,1.5}; B = {0,2,0,2} -> {-1,1,-1,1}.
  // Lag 1 within A: 0.75 - 0.25 + 0.75 = 1.25; within B: -3. Lag 0: 5 + 4 = 9.
  // Lag 2 within A: -0.75 - 0.75 = -1.5; within B: 2. So r(1) = -1.75/9, r(2) = 0.5/9.
  ResidualCorrelationOptions options;
  options.max_lag = 2;
  const auto summary = residual_correlation({{1, 2, 3, 4}, {0, 2, 0, 2}}, {}, options);
  ASSERT_TRUE(summary.is_usable()) << summary.message;
  EXPECT_EQ(summary.n, 8u);
  EXPECT_EQ(summary.segments, 2u);
  EXPECT_NEAR(value_at(summary.autocorrelation, 1), -1.75 / 9, 1e-15);
  EXPECT_NEAR(value_at(summary.autocorrelation, 2), 0.5 / 9, 1e-15);

  // Each record's offset is removed on its own: two white records at +10 and -10 stay white.
  auto a = white_noise(500, 31), b = white_noise(500, 32);
  for (auto& v : a) v += 10;
  for (auto& v : b) v -= 10;
  const auto offsets = residual_correlation({a, b}, {}, {});
  ASSERT_TRUE(offsets.is_usable());
  EXPECT_LT(std::fabs(value_at(offsets.autocorrelation, 1)), offsets.bonferroni_band);
}

TEST(ResidualCorrelation, ShortConstantAndNonFiniteInputGiveAStatus) {
  using Status = ResidualCorrelationSummary::Status;
  EXPECT_EQ(residual_correlation({}, {}, {}).status, Status::too_short);
  EXPECT_EQ(residual_correlation({{1, 2, 3}}, {}, {}).status, Status::too_short);
  // Segments of one sample are left out: eight of them are still too short.
  EXPECT_EQ(residual_correlation(std::vector<std::vector<double>>(8, {1.0}), {}, {}).status, Status::too_short);

  const auto constant = residual_correlation({std::vector<double>(50, 3.0)}, {}, {});
  EXPECT_EQ(constant.status, Status::constant_residuals);
  EXPECT_FALSE(constant.message.empty());
  EXPECT_NE(constant.verdict.find("no residual analysis"), std::string::npos);

  auto e = white_noise(100, 41);
  e[17] = NAN;
  const auto nan = residual_correlation({e}, {}, {});
  EXPECT_EQ(nan.status, Status::invalid_input);
  EXPECT_NE(nan.message.find("residual 18"), std::string::npos) << nan.message;

  const auto mismatched = residual_correlation({white_noise(100, 42)}, {{"x", {white_noise(99, 43)}}}, {});
  EXPECT_EQ(mismatched.status, Status::invalid_input);
  EXPECT_NE(mismatched.message.find("`x`"), std::string::npos);

  ResidualCorrelationOptions bad;
  bad.confidence_level = 1.5;
  EXPECT_EQ(residual_correlation({white_noise(100, 44)}, {}, bad).status, Status::invalid_options);

  // A constant input is reported, not divided by zero; the autocorrelation is still computed.
  const auto flat_input = residual_correlation({white_noise(100, 45)}, {{"x", {std::vector<double>(100, 2.0)}}}, {});
  ASSERT_TRUE(flat_input.is_usable());
  ASSERT_EQ(flat_input.cross.size(), 1u);
  EXPECT_FALSE(flat_input.cross[0].computed);
  EXPECT_NE(flat_input.cross[0].verdict.find("constant"), std::string::npos);
  EXPECT_FALSE(flat_input.brief_report().empty());
}

TEST(ResidualCorrelation, MaxLagNeverExceedsTheLongestSegment) {
  ResidualCorrelationOptions options;
  options.max_lag = 50;
  const auto summary = residual_correlation({white_noise(10, 51), white_noise(10, 52)}, {}, options);
  ASSERT_TRUE(summary.is_usable());
  EXPECT_EQ(summary.max_lag, 9);
  EXPECT_EQ(summary.autocorrelation.lags.size(), 10u);
}

TEST(ResidualCorrelation, ContiguousSegmentsSplitWhereTheKeyChanges) {
  const auto segments = contiguous_segments({0, 0, 0, 1, 1, 0, 2});
  ASSERT_EQ(segments.size(), 4u);
  EXPECT_EQ(segments[0], (std::pair<std::size_t, std::size_t>{0, 3}));
  EXPECT_EQ(segments[1], (std::pair<std::size_t, std::size_t>{3, 5}));
  EXPECT_EQ(segments[2], (std::pair<std::size_t, std::size_t>{5, 6}));
  EXPECT_EQ(segments[3], (std::pair<std::size_t, std::size_t>{6, 7}));
  EXPECT_TRUE(contiguous_segments({}).empty());
}

}  // namespace
}  // namespace sidc
