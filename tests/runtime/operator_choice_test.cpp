// savgol(auto) (runtime/operators/operator_choice.hpp): the arc it chooses against the truth on
// signals with known derivatives and known noise. Its true rms error must be close to that of the
// best arc in hindsight (an oracle that knows the exact derivative), its estimated error close to
// the true one; a constant signal gets the smallest arc, a short record an error naming the
// signal, a signal that is mostly noise a warning. Also the measurement behind the default way to
// second derivatives (direct arc against the first-derivative arc repeated, docs/accuracy.md).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <random>
#include <vector>

#include "compiler/pipeline.hpp"
#include "ir/settings.hpp"
#include "runtime/operators/operator_choice.hpp"

namespace sidc {
namespace {

struct Signal {
  const char* name;
  std::function<double(double, int)> f;  // value (order 0) and derivatives of order 1, 2
};

// y = e^{-0.1 t} (sin 1.3 t + 0.5 sin 3.1 t) and its derivatives, by hand.
double tones(double t, int order) {
  const double a = -0.1;
  auto part = [&](double w, double c) {  // d^k/dt^k of c e^{a t} sin(w t)
    const double e = c * std::exp(a * t), s = std::sin(w * t), k = std::cos(w * t);
    if (order == 0) return e * s;
    if (order == 1) return e * (a * s + w * k);
    return e * ((a * a - w * w) * s + 2 * a * w * k);
  };
  return part(1.3, 1.0) + part(3.1, 0.5);
}

double slow(double t, int order) {
  const double w = 0.4;
  return order == 0 ? std::sin(w * t) : order == 1 ? w * std::cos(w * t) : -w * w * std::sin(w * t);
}

double fast(double t, int order) {  // 40 samples a period at step 0.01
  const double w = 2 * M_PI / 0.4;
  return order == 0 ? std::sin(w * t) : order == 1 ? w * std::cos(w * t) : -w * w * std::sin(w * t);
}

const std::vector<Signal>& signals() {
  static const std::vector<Signal> s{{"two damped tones", tones}, {"slow sine", slow}, {"fast sine", fast}};
  return s;
}

constexpr double kStep = 0.01;
constexpr std::size_t kSamples = 2001;

std::vector<double> record_of(const Signal& s, double relative_noise, unsigned seed) {
  std::vector<double> y(kSamples);
  double mean = 0, ss = 0;
  for (std::size_t i = 0; i < kSamples; ++i) mean += (y[i] = s.f(static_cast<double>(i) * kStep, 0));
  mean /= kSamples;
  for (double v : y) ss += (v - mean) * (v - mean);
  const double sigma = relative_noise * std::sqrt(ss / kSamples);
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (double& v : y) v += sigma * normal(rng);
  return y;
}

// The true rms error of an arc's order-th derivative over the samples 10% in from each end.
double true_rms(const Signal& s, const std::vector<double>& y, int order, const DerivativeOptions& arc) {
  auto estimate = estimate_derivative(y, kStep, order, arc);
  EXPECT_TRUE(std::holds_alternative<std::vector<double>>(estimate));
  const auto& d = std::get<std::vector<double>>(estimate);
  double ss = 0;
  std::size_t n = 0;
  for (std::size_t i = kSamples / 10; i < kSamples - kSamples / 10; ++i) {
    const double e = d[i] - s.f(static_cast<double>(i) * kStep, order);
    ss += e * e, ++n;
  }
  return std::sqrt(ss / static_cast<double>(n));
}

// The best arc in hindsight among the candidates savgol(auto) may choose from.
double oracle_rms(const Signal& s, const std::vector<double>& y, int order, bool repeated) {
  double best = INFINITY;
  const int widest = static_cast<int>(2 * (kAutoEdgeShare * kSamples / (repeated ? order : 1)) + 1);
  for (int w = 5; w <= widest; w += 2)
    for (int p = repeated ? 1 : order; p <= (repeated ? 5 : order + 4); p += 2) {
      if (p + 2 > w - 1) continue;
      DerivativeOptions arc;
      arc.window = w;
      arc.polyorder = p;
      arc.second = repeated ? DerivativeOptions::Second::repeated : DerivativeOptions::Second::direct;
      best = std::min(best, true_rms(s, y, order, arc));
    }
  return best;
}

ArcChoice chosen(const std::vector<double>& y, int order, AutoForms forms = AutoForms::direct) {
  auto c = choose_arc(y, kStep, order, estimate_noise_level(y), DerivativeOptions{}, forms, "y", "test.csv");
  EXPECT_TRUE(std::holds_alternative<ArcChoice>(c)) << render(std::get<Diagnostic>(c));
  return std::get<ArcChoice>(c);
}

TEST(OperatorChoice, CloseToTheBestArcInHindsight) {
  for (const auto& s : signals())
    for (double noise : {1e-3, 1e-2})
      for (int order : {1, 2}) {
        const auto y = record_of(s, noise, 17);
        const ArcChoice c = chosen(y, order);
        const double truth = true_rms(s, y, order, c.arc);
        const double oracle = oracle_rms(s, y, order, false);
        EXPECT_LE(truth, 1.6 * oracle) << s.name << " noise " << noise << " order " << order << ": " << c.describe();
        // The criterion's own estimate of the error is of the right size.
        EXPECT_GT(c.rms_error(), truth / 2.5) << s.name << " noise " << noise << " order " << order;
        EXPECT_LT(c.rms_error(), truth * 2.5) << s.name << " noise " << noise << " order " << order;
      }
}

TEST(OperatorChoice, MoreNoiseWiderArcs) {
  const auto quiet = chosen(record_of(signals()[0], 1e-4, 3), 1);
  const auto loud = chosen(record_of(signals()[0], 3e-2, 3), 1);
  EXPECT_LT(quiet.arc.window, loud.arc.window);
  EXPECT_GT(loud.noise, quiet.noise);
}

TEST(OperatorChoice, ByMeasurementTheDirectArcIsTheBetterWayToSecondDerivatives) {
  // docs/accuracy.md quotes these numbers: the true rms error of y'' under savgol(auto) each way.
  // Geometric means over the signals: about even at 0.1% noise, the direct arc clearly ahead at 1%
  // (and on the damped oscillator's fit, docs/accuracy.md).
  for (double noise : {1e-3, 1e-2}) {
    double direct_total = 0, repeated_total = 0;
    for (const auto& s : signals()) {
      const auto y = record_of(s, noise, 23);
      const double direct = true_rms(s, y, 2, chosen(y, 2, AutoForms::direct).arc);
      const double repeated = true_rms(s, y, 2, chosen(y, 2, AutoForms::repeated).arc);
      std::cout << "  y'' of " << s.name << " at noise " << noise << ": direct " << direct << ", repeated " << repeated << "\n";
      direct_total += std::log(direct), repeated_total += std::log(repeated);
    }
    if (noise < 5e-3) EXPECT_LT(direct_total, repeated_total + 3 * std::log(1.2)) << "noise " << noise;
    else EXPECT_LT(direct_total, repeated_total - 3 * std::log(1.2)) << "noise " << noise;
  }
}

TEST(OperatorChoice, AConstantSignalGetsTheSmallestArc) {
  const std::vector<double> y(200, 1.5);
  for (int order : {1, 2, 3}) {
    const ArcChoice c = chosen(y, order);
    EXPECT_TRUE(c.noise_free);
    EXPECT_EQ(c.arc.window, order == 3 ? 7 : 5);
    EXPECT_EQ(c.arc.polyorder, order);
    EXPECT_EQ(c.rms_error(), 0.0);
  }
  const ArcChoice repeated = chosen(y, 2, AutoForms::repeated);
  EXPECT_EQ(repeated.arc.window, 5);
  EXPECT_EQ(repeated.arc.polyorder, 1);
  EXPECT_EQ(repeated.arc.second, DerivativeOptions::Second::repeated);
}

TEST(OperatorChoice, ARecordTooShortForAnyArcIsAnErrorNamingTheSignal) {
  const std::vector<double> y{1, 2, 3, 4};
  auto c = choose_arc(y, 0.1, 1, estimate_noise_level(y), DerivativeOptions{}, AutoForms::direct, "speed", "short.csv");
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(c));
  const Diagnostic& d = std::get<Diagnostic>(c);
  EXPECT_EQ(d.code, "data-too-short-for-arc");
  EXPECT_NE(d.message.find("`speed`"), std::string::npos);
  EXPECT_NE(d.message.find("short.csv"), std::string::npos);
  // Five samples are enough for the smallest first-derivative arc.
  EXPECT_TRUE(std::holds_alternative<ArcChoice>(
      choose_arc(std::vector<double>{1, 2, 3, 4, 5}, 0.1, 1, NoiseLevel{}, DerivativeOptions{}, AutoForms::direct, "speed", "short.csv")));
}

TEST(OperatorChoice, AShortRecordKeepsItsArcsWithinTheEdgeShare) {
  const auto y = record_of(signals()[1], 1e-2, 5);
  const std::vector<double> short_y(y.begin(), y.begin() + 300);
  const ArcChoice c = chosen(short_y, 2);
  EXPECT_LE(c.arc.window / 2, static_cast<int>(kAutoEdgeShare * 300));
}

ir::Model model_of(const std::string& text) {
  const auto r = compile(std::make_shared<const SourceFile>("m.sid", text), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return r.ok() ? *r.integrated : ir::Model{};
}

TEST(OperatorChoice, ARecordsReportNamesNoisyAndConstantSignals) {
  const ir::Model m = model_of("model m\ninput u\noutput y\nparam a, b\na*y' + b*y = u\n");
  SampledRecord r;
  r.path = "r.csv";
  r.step = kStep;
  for (std::size_t i = 0; i < kSamples; ++i) r.time.push_back(static_cast<double>(i) * kStep);
  std::mt19937 rng(1);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (std::size_t i = 0; i < kSamples; ++i) r.signals["y"].push_back(0.01 * std::sin(r.time[i]) + normal(rng));
  r.signals["u"] = std::vector<double>(kSamples, 2.0);
  EvaluationOptions o;
  o.automatic_derivative = true;
  auto report = choose_operators(r, m, o);
  ASSERT_TRUE(std::holds_alternative<OperatorReport>(report));
  const auto& rep = std::get<OperatorReport>(report);
  ASSERT_EQ(rep.noise.size(), 2u);
  ASSERT_EQ(rep.warnings.size(), 2u);
  EXPECT_EQ(rep.warnings[0].code, "data-constant-signal");  // u, in name order
  EXPECT_NE(rep.warnings[0].message.find("`u`"), std::string::npos);
  EXPECT_EQ(rep.warnings[1].code, "data-noise-exceeds-variation");
  EXPECT_NE(rep.warnings[1].message.find("`y`"), std::string::npos);
  EXPECT_EQ(rep.warnings[1].severity, Severity::warning);
  ASSERT_EQ(rep.arcs.size(), 1u);  // y' only
  EXPECT_EQ(rep.arcs[0].signal, "y");
  EXPECT_EQ(rep.arcs[0].order, 1);
  // The options carry the arc; a fixed operator is left alone.
  auto with = operators_for_record(o, r, m);
  ASSERT_TRUE(std::holds_alternative<EvaluationOptions>(with));
  EXPECT_EQ(derivative_options_for(std::get<EvaluationOptions>(with), "y", 1).window, rep.arcs[0].arc.window);
  EvaluationOptions fixed;
  EXPECT_EQ(derivative_options_for(fixed, "y", 1).window, 7);
  EXPECT_THROW(derivative_options_for(o, "y", 1), std::logic_error);
}

TEST(OperatorChoice, TheSettingParsesAutoAndKeepsExplicitArcs) {
  ASSERT_TRUE(parse_moving_arc("savgol(auto)"));
  EXPECT_TRUE(parse_moving_arc("savgol( auto )")->automatic);
  EXPECT_FALSE(parse_moving_arc("savgol(9, 3)")->automatic);
  EXPECT_EQ(parse_moving_arc("savgol(9, 3)")->window, 9);
  EXPECT_TRUE(check_setting("derivative", "savgol(auto)").expected.empty());
  EXPECT_FALSE(check_setting("smooth_before_integration", "savgol(auto)").expected.empty());
  EXPECT_TRUE(evaluation_settings(ir::Settings{}).derivative.automatic);  // the default
}

}  // namespace
}  // namespace sidc
