// Local fits (issue 18, thesis chapter V): the sliding factor against fresh QR fits of the same
// rows, exponential forgetting against the weighted least squares it stands for, the safeguard of
// the downdate, and local_fit() recovering a drifting stiffness and a jump of damping.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "compiler/pipeline.hpp"
#include "runtime/solve/local_fit.hpp"
#include "runtime/solve/sliding_factor.hpp"

#include "support/simulation.hpp"

namespace sidc {
namespace {

// The least-squares estimates and standard errors of rows [first, last) of [A b], fresh.
void fresh_fit(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, Eigen::Index first, Eigen::Index last, Eigen::VectorXd& x,
               Eigen::VectorXd& se) {
  const Eigen::MatrixXd a = A.middleRows(first, last - first);
  const Eigen::VectorXd y = b.segment(first, last - first);
  x = a.householderQr().solve(y);
  const double s2 = (y - a * x).squaredNorm() / static_cast<double>(a.rows() - a.cols());
  se = (s2 * (a.transpose() * a).inverse().diagonal()).cwiseSqrt();
}

double relative(const std::vector<double>& got, const Eigen::VectorXd& want) {
  double d = 0;
  for (Eigen::Index j = 0; j < want.size(); ++j) d = std::max(d, std::abs(got[static_cast<std::size_t>(j)] - want(j)));
  return d / want.cwiseAbs().maxCoeff();
}

// Correlated, unevenly scaled columns, as a design of derivatives and products is.
void random_problem(Eigen::Index n, Eigen::Index p, Eigen::MatrixXd& A, Eigen::VectorXd& b) {
  std::mt19937 engine(7);
  std::normal_distribution<double> normal;
  A.resize(n, p);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < p; ++j) A(i, j) = std::pow(10.0, static_cast<double>(j % 4) - 1) * (normal(engine) + 0.5 * std::sin(0.01 * static_cast<double>(i * (j + 1))));
  Eigen::VectorXd truth = Eigen::VectorXd::LinSpaced(p, 1, 2);
  b = A * truth;
  for (Eigen::Index i = 0; i < n; ++i) b(i) += 0.01 * normal(engine);
}

TEST(SlidingFactor, UpdatedAndDowndatedAgreesWithAFreshFitOfEveryWindow) {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  const Eigen::Index n = 3000, p = 8, W = 120;
  random_problem(n, p, A, b);
  for (Eigen::Index stride : {1, 5}) {
    SlidingFactor f(static_cast<int>(p));
    for (Eigen::Index i = 0; i < W; ++i) f.add(A.row(i).eval().data(), b(i));
    double worst = 0, worst_se = 0;
    for (Eigen::Index k = 0;; ++k) {
      const Eigen::Index first = k * stride;
      const SlidingSolution s = f.solve(static_cast<double>(W), 0);
      ASSERT_EQ(s.rank, p);
      Eigen::VectorXd x, se;
      fresh_fit(A, b, first, first + W, x, se);
      worst = std::max(worst, relative(s.estimates, x));
      worst_se = std::max(worst_se, relative(s.standard_errors, se));
      if (first + stride + W > n) break;
      for (Eigen::Index i = first + W; i < first + W + stride; ++i) f.add(A.row(i).eval().data(), b(i));
      for (Eigen::Index i = first; i < first + stride; ++i) ASSERT_TRUE(f.remove(A.row(i).eval().data(), b(i)));
    }
    EXPECT_LT(worst, 1e-10) << "stride " << stride;
    EXPECT_LT(worst_se, 1e-9) << "stride " << stride;
  }
}

TEST(SlidingFactor, ResidualSumOfSquaresFollowsTheWindow) {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  random_problem(400, 4, A, b);
  SlidingFactor f(4);
  for (Eigen::Index i = 0; i < 300; ++i) f.add(A.row(i).eval().data(), b(i));
  for (Eigen::Index i = 0; i < 100; ++i) ASSERT_TRUE(f.remove(A.row(i).eval().data(), b(i)));
  Eigen::VectorXd x, se;
  fresh_fit(A, b, 100, 300, x, se);
  const double G = (b.segment(100, 200) - A.middleRows(100, 200) * x).squaredNorm();
  EXPECT_NEAR(f.solve(200, 0).G, G, 1e-10 * G);
}

TEST(SlidingFactor, ForgettingIsWeightedLeastSquares) {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  const Eigen::Index n = 500, p = 5;
  random_problem(n, p, A, b);
  const double lambda = 0.98;
  SlidingFactor f(static_cast<int>(p));
  for (Eigen::Index i = 0; i < n; ++i) {
    f.scale(std::sqrt(lambda));
    f.add(A.row(i).eval().data(), b(i));
  }
  Eigen::VectorXd w(n);
  for (Eigen::Index i = 0; i < n; ++i) w(i) = std::pow(lambda, 0.5 * static_cast<double>(n - 1 - i));
  const Eigen::VectorXd x = (w.asDiagonal() * A).householderQr().solve(w.asDiagonal() * b);
  EXPECT_LT(relative(f.solve(static_cast<double>(n), 0).estimates, x), 1e-12);
}

TEST(SlidingFactor, RefusesADowndateThatWouldLoseTheOnlyInformationOfAColumn) {
  SlidingFactor f(2);
  const double rows[4][2] = {{1, 0}, {2, 0}, {3, 0}, {0, 1}};
  for (const auto& r : rows) f.add(r, r[0] + r[1]);
  const SlidingSolution before = f.solve(4, 0);
  ASSERT_EQ(before.rank, 2);
  EXPECT_FALSE(f.remove(rows[3], 1));  // the last row alone carries the second column
  const SlidingSolution after = f.solve(4, 0);
  EXPECT_EQ(after.estimates, before.estimates);  // untouched
  ASSERT_TRUE(f.remove(rows[0], 1));
  EXPECT_EQ(f.solve(3, 0).rank, 2);
}

TEST(SlidingFactor, RankDeficientRowsGiveNoEstimate) {
  SlidingFactor f(3);
  const double rows[3][3] = {{1, 2, 3}, {2, 4, 1}, {3, 6, 2}};  // second column twice the first
  for (const auto& r : rows) f.add(r, 1);
  const SlidingSolution s = f.solve(3, 0);
  EXPECT_EQ(s.rank, 2);
  EXPECT_TRUE(s.estimates.empty());
}

// y'' + c(t) y' + k(t) y = x: a mass-spring-damper whose stiffness or damping changes in time,
// driven by a sum of sines, solved by RK4 with 20 substeps a sample; noise `share` of sd(y).
SampledRecord drifting_oscillator(const std::function<double(double)>& c, const std::function<double(double)>& k, double T, double h,
                                  double share) {
  auto x = [](double t) { return std::sin(0.7 * t) + 0.6 * std::sin(2.3 * t + 1) + 0.4 * std::sin(4.1 * t + 2); };
  auto f = [&](double t, double y, double v, double& dy, double& dv) {
    dy = v;
    dv = x(t) - c(t) * v - k(t) * y;
  };
  SampledRecord r;
  r.path = "drift.csv";
  r.step = h;
  double y = 0, v = 0;
  const int sub = 20;
  const double d = h / sub;
  std::vector<double> ys, xs;
  const auto n = static_cast<std::size_t>(std::llround(T / h)) + 1;
  for (std::size_t s = 0; s < n; ++s) {
    const double t = static_cast<double>(s) * h;
    r.time.push_back(t);
    ys.push_back(y);
    xs.push_back(x(t));
    for (int j = 0; j < sub; ++j) {
      const double u = t + j * d;
      double a1, b1, a2, b2, a3, b3, a4, b4;
      f(u, y, v, a1, b1);
      f(u + d / 2, y + d / 2 * a1, v + d / 2 * b1, a2, b2);
      f(u + d / 2, y + d / 2 * a2, v + d / 2 * b2, a3, b3);
      f(u + d, y + d * a3, v + d * b3, a4, b4);
      y += d / 6 * (a1 + 2 * a2 + 2 * a3 + a4);
      v += d / 6 * (b1 + 2 * b2 + 2 * b3 + b4);
    }
  }
  std::mt19937 engine(11);
  testing::add_noise(ys, share, engine);
  r.signals["y"] = std::move(ys);
  r.signals["x"] = std::move(xs);
  return r;
}

ir::Model oscillator_model(const std::string& form = "derivative") {
  const auto r = compile(std::make_shared<const SourceFile>("m.sid", "input x\noutput y\nparam m, c, k\nset form = " + form + "\nm*y'' + c*y' + k*y = x\n"), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return *r.integrated;
}

LocalFitSummary local(const ir::Model& model, const SampledRecord& record, const LocalFitOptions& o) {
  auto result = local_fit(model, {record}, FitOptions{}, o);
  EXPECT_TRUE(std::holds_alternative<LocalFitSummary>(result)) << render(std::get<Diagnostic>(result));
  return std::holds_alternative<LocalFitSummary>(result) ? std::get<LocalFitSummary>(std::move(result)) : LocalFitSummary{};
}

// Issue 18's target: the drifting stiffness within 1% of the truth away from the ends, at 0.1% noise.
// The weak form's rows are local (each a subdomain's integral) and take no derivative of the
// noisy record, so a window of them estimates the parameters of that stretch of time.
TEST(LocalFit, RecoversADriftingStiffness) {
  auto k = [](double t) { return 4 * (1 + 0.5 * t / 100); };
  const SampledRecord record = drifting_oscillator([](double) { return 0.4; }, k, 100, 0.01, 0.001);
  LocalFitOptions o;
  o.width = 10;
  o.stride = 25;
  const LocalFitSummary s = local(oscillator_model("weak"), record, o);
  ASSERT_EQ(s.groups.size(), 1u);
  
  const LocalRecordFit& r = s.groups[0].records[0];
  ASSERT_GT(r.windows(), 300u);
  double worst = 0;
  const std::size_t p = s.groups[0].columns.size();
  std::size_t checked = 0;
  for (std::size_t w = 0; w < r.windows(); ++w) {
    ASSERT_EQ(r.rank[w], static_cast<int>(p));
    if (r.t_center[w] < o.width || r.t_center[w] > 100 - o.width) continue;  // away from the record's ends
    ++checked;
    const double m = r.estimates[w * p], ks = r.estimates[w * p + 2] / m;  // m = 1 in truth: k relative to it
    worst = std::max(worst, std::abs(ks / k(r.t_center[w]) - 1));
  }
  EXPECT_GT(checked, 250u);
  EXPECT_LT(worst, 0.01);
  EXPECT_LT(s.max_drift, 1e-10);
}

TEST(LocalFit, FollowsAJumpOfDampingWithinAWindow) {
  auto c = [](double t) { return t < 50 ? 0.3 : 0.9; };
  const SampledRecord record = drifting_oscillator(c, [](double) { return 4.0; }, 100, 0.01, 0.001);
  LocalFitOptions o;
  o.width = 8;
  o.stride = 10;
  const LocalFitSummary s = local(oscillator_model("weak"), record, o);
  const LocalRecordFit& r = s.groups[0].records[0];
  for (std::size_t w = 0; w < r.windows(); ++w) {
    const double t = r.t_center[w], cs = r.estimates[w * 3 + 1] / r.estimates[w * 3];
    if (std::abs(t - 50) > o.width / 2 + 0.1) EXPECT_NEAR(cs, c(t), 0.03 * c(t)) << "t = " << t;
    else EXPECT_TRUE(cs > 0.25 && cs < 0.95) << "t = " << t;  // a mixture while the window straddles the jump
  }
}

// Windows slid with stride 1 against every window fitted fresh (stride >= width).
TEST(LocalFit, SlidingAgreesWithFreshWindowsToRounding) {
  const SampledRecord record = drifting_oscillator([](double) { return 0.4; }, [](double) { return 4.0; }, 30, 0.01, 0.01);
  LocalFitOptions slid;
  slid.width = 2;
  slid.piece_turnovers = 1000;  // one piece per thread: many updates between fresh factors
  slid.threads = 1;
  const LocalFitSummary a = local(oscillator_model(), record, slid);
  LocalFitOptions fresh = slid;
  fresh.stride = 200;  // == the window: every window factored from scratch
  const LocalFitSummary b = local(oscillator_model(), record, fresh);
  const LocalRecordFit& ra = a.groups[0].records[0];
  const LocalRecordFit& rb = b.groups[0].records[0];
  ASSERT_GT(rb.windows(), 10u);
  double worst = 0;
  for (std::size_t w = 0; w < rb.windows(); ++w) {
    const std::size_t v = w * 200;
    ASSERT_LT(v, ra.windows());
    EXPECT_DOUBLE_EQ(ra.t_center[v], rb.t_center[w]);
    EXPECT_EQ(ra.n[v], rb.n[w]);
    for (std::size_t j = 0; j < 3; ++j)
      worst = std::max(worst, std::abs(ra.estimates[v * 3 + j] - rb.estimates[w * 3 + j]) / std::abs(rb.estimates[w * 3 + j]));
  }
  EXPECT_LT(worst, 1e-10);
  EXPECT_EQ(a.refused_downdates, 0u);
}

TEST(LocalFit, ThreadsAndPiecesDoNotChangeTheEstimatesBeyondRounding) {
  const SampledRecord record = drifting_oscillator([](double) { return 0.4; }, [](double t) { return 4 + 0.02 * t; }, 30, 0.01, 0.01);
  LocalFitOptions one;
  one.width = 2;
  one.threads = 1;
  one.piece_turnovers = 1000;
  LocalFitOptions many = one;
  many.threads = 3;
  many.piece_turnovers = 1;
  const LocalRecordFit a = local(oscillator_model(), record, one).groups[0].records[0];
  const LocalFitSummary sb = local(oscillator_model(), record, many);
  const LocalRecordFit& b = sb.groups[0].records[0];
  ASSERT_EQ(a.windows(), b.windows());
  for (std::size_t w = 0; w < a.windows(); ++w) {  // norm-wise: a parameter near 0 has no relative digits to keep
    double size = 0;
    for (std::size_t j = 0; j < 3; ++j) size = std::max(size, std::abs(a.estimates[w * 3 + j]));
    for (std::size_t j = 0; j < 3; ++j) EXPECT_NEAR(a.estimates[w * 3 + j], b.estimates[w * 3 + j], 1e-10 * size);
  }
  EXPECT_GT(sb.drift_checks, 5u);
  EXPECT_LT(sb.max_drift, 1e-10);
}

TEST(LocalFit, ForgettingFollowsADriftAndMatchesOnePassOverThreads) {
  const SampledRecord record = drifting_oscillator([](double) { return 0.4; }, [](double t) { return 4 + 0.02 * t; }, 60, 0.01, 0.001);
  LocalFitOptions o;
  o.forget = 0.999;
  o.stride = 50;
  o.threads = 3;
  o.piece_turnovers = 1;
  const LocalFitSummary s = local(oscillator_model("weak"), record, o);
  LocalFitOptions single = o;
  single.threads = 1;
  single.piece_turnovers = 1000;
  const LocalFitSummary one = local(oscillator_model("weak"), record, single);
  const LocalRecordFit& r = s.groups[0].records[0];
  const LocalRecordFit& q = one.groups[0].records[0];
  ASSERT_EQ(r.windows(), q.windows());
  for (std::size_t w = 0; w < r.windows(); ++w) {
    if (r.rank[w] < 3) continue;
    for (std::size_t j = 0; j < 3; ++j) EXPECT_NEAR(r.estimates[w * 3 + j], q.estimates[w * 3 + j], 1e-9 * std::abs(q.estimates[w * 3 + j]));
    if (r.t_center[w] > 20) {  // at the rows' weighted mean time, a forgetting time (10) back
      const double k = r.estimates[w * 3 + 2] / r.estimates[w * 3];
      EXPECT_NEAR(k, 4 + 0.02 * r.t_center[w], 0.015 * k) << "t = " << r.t_center[w];
    }
  }
}

TEST(LocalFit, RefusesAWindowShorterThanTheParametersOrLongerThanTheRecord) {
  const SampledRecord record = drifting_oscillator([](double) { return 0.4; }, [](double) { return 4.0; }, 10, 0.01, 0.01);
  LocalFitOptions o;
  o.width = 0.01;  // one sample, one row, three parameters
  auto short_window = local_fit(oscillator_model(), {record}, FitOptions{}, o);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(short_window));
  EXPECT_EQ(std::get<Diagnostic>(short_window).code, "local-window-too-short");
  o.width = 50;
  auto long_window = local_fit(oscillator_model(), {record}, FitOptions{}, o);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(long_window));
  EXPECT_EQ(std::get<Diagnostic>(long_window).code, "local-window-too-long");
}

// An input that is zero for a while: the windows inside that stretch cannot tell its parameter,
// are marked (rank < p, no estimate), and the windows after it are right again.
TEST(LocalFit, MarksRankDeficientWindowsAndRecoversAfterThem) {
  SampledRecord r;
  r.path = "gap.csv";
  r.step = 0.01;
  std::vector<double> y, u;
  for (int s = 0; s < 3000; ++s) {
    const double t = s * 0.01, on = (t > 10 && t < 18) ? 0.0 : 1.0;
    r.time.push_back(t);
    u.push_back(on * std::sin(3 * t));
    y.push_back(std::cos(t) + 2 * on * std::sin(3 * t));
  }
  r.signals["y"] = y;
  r.signals["u"] = u;
  const auto compiled = compile(std::make_shared<const SourceFile>("g.sid", "input u\noutput y\nparam a, b\ny = a*u + b*cos(t)\n"), {});
  ASSERT_TRUE(compiled.ok()) << compiled.diagnostics.render_all();
  LocalFitOptions o;
  o.width = 2;
  o.stride = 7;
  const LocalFitSummary s = local(*compiled.integrated, r, o);
  const LocalRecordFit& f = s.groups[0].records[0];
  std::size_t deficient = 0;
  for (std::size_t w = 0; w < f.windows(); ++w) {
    if (f.t_center[w] > 11.2 && f.t_center[w] < 16.8) {
      EXPECT_EQ(f.rank[w], 1) << "t = " << f.t_center[w];
      EXPECT_TRUE(std::isnan(f.estimates[w * 2]));
      ++deficient;
    } else if (f.rank[w] == 2) {
      EXPECT_NEAR(f.estimates[w * 2], 2, 1e-9);
      EXPECT_NEAR(f.estimates[w * 2 + 1], 1, 1e-9);
    }
  }
  EXPECT_GT(deficient, 50u);
  EXPECT_EQ(s.rank_deficient, deficient + (s.rank_deficient - deficient));  // every marked window counted
  EXPECT_GT(s.refused_downdates, 0u);
}

}  // namespace
}  // namespace sidc
