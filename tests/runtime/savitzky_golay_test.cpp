// Moving-arc weights against external references (central_coefficients.csv, scipy_examples.csv),
// against the thesis' printed formulas (eqs. 3-1.2 ... 3-1.8), and by their defining properties;
// derivative estimates on polynomials, on sin(4 pi t), and on the thesis' Appendix A record.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "runtime/operators/savitzky_golay.hpp"

namespace sidc {
namespace {

const std::string kCoefficientData = std::string(SIDC_SOURCE_DIR "/tests/runtime/data/");

std::vector<double> weights_of(int window, int polyorder, int derivative, int position = -1, double delta = 1.0) {
  auto result = savitzky_golay_weights({window, polyorder, derivative, position, delta});
  if (auto* d = std::get_if<Diagnostic>(&result)) {
    ADD_FAILURE() << render(*d);
    return {};
  }
  return std::get<std::vector<double>>(std::move(result));
}

std::vector<double> derivative_of(std::span<const double> y, double delta, int order, const DerivativeOptions& o) {
  auto result = estimate_derivative(y, delta, order, o);
  if (auto* d = std::get_if<Diagnostic>(&result)) {
    ADD_FAILURE() << render(*d);
    return std::vector<double>(y.size(), NAN);
  }
  return std::get<std::vector<double>>(std::move(result));
}

// |a - b| within `relative` of the larger magnitude in `b` (zeros in b are compared on that scale).
void expect_weights_near(const std::vector<double>& a, const std::vector<double>& b, double relative,
                         const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  double scale = 0;
  for (double v : b) scale = std::max(scale, std::fabs(v));
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], relative * scale) << what << " [" << i << "]";
}

// ---- the reference files -------------------------------------------------------------------------

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"') quoted = !quoted;
    else if (c == ',' && !quoted) fields.emplace_back();
    else if (c != '\r') fields.back() += c;
  }
  return fields;
}

std::vector<std::vector<std::string>> read_table(const std::string& path, std::vector<std::string>& header) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::string line;
  std::getline(in, line);
  header = split_csv_line(line);
  std::vector<std::vector<std::string>> rows;
  while (std::getline(in, line))
    if (!line.empty()) rows.push_back(split_csv_line(line));
  return rows;
}

std::size_t index_of(const std::vector<std::string>& header, const std::string& name) {
  const auto it = std::find(header.begin(), header.end(), name);
  EXPECT_NE(it, header.end()) << name;
  return static_cast<std::size_t>(it - header.begin());
}

double rational(const std::string& text) {  // "9/35", "-1/7", "6", "0.5"
  const auto slash = text.find('/');
  if (slash == std::string::npos) return std::stod(text);
  return std::stod(text.substr(0, slash)) / std::stod(text.substr(slash + 1));
}

std::vector<double> rationals(const std::string& list) {
  std::vector<double> out;
  std::istringstream in(list);
  for (std::string item; in >> item;) out.push_back(rational(item));
  return out;
}

TEST(SavitzkyGolayWeights, CentralCoefficientsFileEveryRow) {
  std::vector<std::string> header;
  const auto rows = read_table(kCoefficientData + "central_coefficients.csv", header);
  ASSERT_EQ(rows.size(), 12u);
  const std::vector<std::string> cells = {"c_m3", "c_m2", "c_m1", "c_0", "c_p1", "c_p2", "c_p3"};
  for (const auto& row : rows) {
    const int window = std::stoi(row[index_of(header, "window")]);
    const int polyorder = std::stoi(row[index_of(header, "polyorder")]);
    const int deriv = std::stoi(row[index_of(header, "deriv")]);
    const double divisor = std::stod(row[index_of(header, "divisor")]);
    std::vector<double> expected;
    for (const auto& name : cells) {
      const std::string& cell = row[index_of(header, name)];
      if (!cell.empty()) expected.push_back(std::stod(cell) / divisor);
    }
    ASSERT_EQ(expected.size(), static_cast<std::size_t>(window));
    expect_weights_near(weights_of(window, polyorder, deriv), expected, 1e-13,
                        "window " + std::to_string(window) + " order " + std::to_string(polyorder) + " d" +
                            std::to_string(deriv));
  }
}

TEST(SavitzkyGolayWeights, ScipyExamplesEveryRow) {
  std::vector<std::string> header;
  const auto rows = read_table(kCoefficientData + "scipy_examples.csv", header);
  ASSERT_EQ(rows.size(), 21u);
  int checked = 0;
  std::vector<std::string> skipped;
  for (const auto& row : rows) {
    const std::string& name = row[index_of(header, "case")];
    const std::string& function = row[index_of(header, "function")];
    const int window = std::stoi(row[index_of(header, "window")]);
    const int polyorder = std::stoi(row[index_of(header, "polyorder")]);
    const int deriv = std::stoi(row[index_of(header, "deriv")]);
    const double delta = std::stod(row[index_of(header, "delta")]);
    const std::string& pos = row[index_of(header, "pos")];
    const std::string& use = row[index_of(header, "use")];
    const std::string& mode = row[index_of(header, "mode")];
    const std::vector<double> input = rationals(row[index_of(header, "input")]);
    const std::vector<double> expected = rationals(row[index_of(header, "expected_exact")]);
    if (function == "savgol_coeffs") {
      std::vector<double> w = weights_of(window, polyorder, deriv, pos.empty() ? -1 : std::stoi(pos), delta);
      if (use == "conv") std::reverse(w.begin(), w.end());  // SciPy's default order is for convolution
      expect_weights_near(w, expected, 1e-13, name);
      ++checked;
    } else if (function.rfind("savgol_coeffs(...).dot(input)", 0) == 0) {
      const std::vector<double> positions = rationals(pos);
      ASSERT_EQ(positions.size(), expected.size()) << name;
      for (std::size_t k = 0; k < positions.size(); ++k) {
        const auto w = weights_of(window, polyorder, deriv, static_cast<int>(positions[k]), delta);
        double value = 0;
        for (std::size_t i = 0; i < w.size(); ++i) value += w[i] * input[i];
        EXPECT_NEAR(value, expected[k], 1e-13 * std::max(1.0, std::fabs(expected[k]))) << name << " pos " << k;
      }
      ++checked;
    } else if (function == "savgol_filter" && mode == "interp") {
      // SciPy's `interp` edges fit the first / last window and evaluate it: our `shorten`.
      DerivativeOptions o;
      o.window = window;
      o.polyorder = polyorder;
      o.second = DerivativeOptions::Second::direct;
      o.edges = DerivativeOptions::Edges::shorten;
      expect_weights_near(derivative_of(input, delta, deriv, o), expected, 1e-13, name);
      ++checked;
    } else {
      // Padding modes (nearest, constant, mirror, wrap) invent samples beyond the record; sidc
      // does not offer them.
      EXPECT_EQ(function, "savgol_filter") << name;
      EXPECT_TRUE(mode == "nearest" || mode == "constant" || mode == "mirror" || mode == "wrap") << name;
      skipped.push_back(name);
    }
  }
  EXPECT_EQ(checked, 14);
  EXPECT_EQ(skipped.size(), 7u);
}

// ---- the thesis' formulas ----------------------------------------------------------------------

std::vector<long long> compose_integers(const std::vector<long long>& a, const std::vector<long long>& b) {
  std::vector<long long> out(a.size() + b.size() - 1, 0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) out[i + j] += a[i] * b[j];
  return out;
}

TEST(ThesisStencils, DerivedWeightsMatchEquations_3_1_2_3_1_3_3_1_6_3_1_7) {
  for (const double delta : {1.0, 0.01, 0.02}) {
    expect_weights_near(weights_of(5, 2, 0, -1, delta), thesis_stencil::smooth_5_quadratic().weights(delta), 1e-15,
                        "eq. 3-1.2");
    expect_weights_near(weights_of(5, 2, 1, -1, delta), thesis_stencil::first_5_quadratic().weights(delta), 1e-15,
                        "eq. 3-1.3");
    expect_weights_near(weights_of(7, 3, 0, -1, delta), thesis_stencil::smooth_7_cubic().weights(delta), 1e-15,
                        "eq. 3-1.6");
    expect_weights_near(weights_of(7, 3, 1, -1, delta), thesis_stencil::first_7_cubic().weights(delta), 1e-15,
                        "eq. 3-1.7");
  }
}

TEST(ThesisStencils, RepeatedFirstDerivativeIsEquations_3_1_5_and_3_1_8) {
  // Exactly, in integers: eq. 3-1.3 applied twice (eq. 3-1.4) expands to eq. 3-1.5, eq. 3-1.7
  // applied twice to eq. 3-1.8.
  const auto d5 = thesis_stencil::first_5_quadratic();
  const auto dd5 = thesis_stencil::second_5_repeated();
  EXPECT_EQ(compose_integers(d5.numerators, d5.numerators), dd5.numerators);
  EXPECT_EQ(d5.divisor * d5.divisor, dd5.divisor);
  const auto d7 = thesis_stencil::first_7_cubic();
  const auto dd7 = thesis_stencil::second_7_repeated();
  EXPECT_EQ(compose_integers(d7.numerators, d7.numerators), dd7.numerators);
  EXPECT_EQ(d7.divisor * d7.divisor, dd7.divisor);
  // And with the derived weights in floating point.
  const double delta = 0.01;
  const auto w7 = weights_of(7, 3, 1, -1, delta);
  expect_weights_near(compose_stencils(w7, w7), dd7.weights(delta), 1e-14, "eq. 3-1.8");
  const auto w5 = weights_of(5, 2, 1, -1, delta);
  expect_weights_near(compose_stencils(w5, w5), dd5.weights(delta), 1e-14, "eq. 3-1.5");
}

TEST(ThesisStencils, EstimatesApplyTheEquationsAtInteriorSamples) {
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, 1);
  std::vector<double> y(60);
  for (double& v : y) v = noise(rng);
  const double delta = 0.02;
  struct Case {
    int window, polyorder, order;
    DerivativeOptions::Second second;
    IntegerStencil stencil;
  };
  const Case cases[] = {
      {5, 2, 0, DerivativeOptions::Second::repeated, thesis_stencil::smooth_5_quadratic()},
      {5, 2, 1, DerivativeOptions::Second::repeated, thesis_stencil::first_5_quadratic()},
      {5, 2, 2, DerivativeOptions::Second::repeated, thesis_stencil::second_5_repeated()},
      {7, 3, 0, DerivativeOptions::Second::repeated, thesis_stencil::smooth_7_cubic()},
      {7, 3, 1, DerivativeOptions::Second::repeated, thesis_stencil::first_7_cubic()},
      {7, 3, 2, DerivativeOptions::Second::repeated, thesis_stencil::second_7_repeated()},
      // Direct second derivative of the 7-point cubic: (5 0 -3 -4 -3 0 5) / 42 (central_coefficients.csv).
      {7, 3, 2, DerivativeOptions::Second::direct, IntegerStencil{2, 42, {5, 0, -3, -4, -3, 0, 5}}},
  };
  for (const Case& c : cases) {
    DerivativeOptions o;
    o.window = c.window;
    o.polyorder = c.polyorder;
    o.second = c.second;
    const auto estimate = derivative_of(y, delta, c.order, o);
    const auto w = c.stencil.weights(delta);
    const int h = c.stencil.half_width();
    ASSERT_EQ(samples_lost_each_side(c.order, o), h);
    for (int n = 0; n < static_cast<int>(y.size()); ++n) {
      if (n < h || n + h >= static_cast<int>(y.size())) {
        EXPECT_TRUE(std::isnan(estimate[static_cast<std::size_t>(n)])) << "sample " << n << " must be dropped";
        continue;
      }
      double expected = 0;
      for (int i = -h; i <= h; ++i) expected += w[static_cast<std::size_t>(i + h)] * y[static_cast<std::size_t>(n + i)];
      EXPECT_NEAR(estimate[static_cast<std::size_t>(n)], expected, 1e-12 * (1 + std::fabs(expected)))
          << "window " << c.window << " order " << c.order << " sample " << n;
    }
  }
}

// ---- defining properties -----------------------------------------------------------------------

// The least-squares weights are the only weights that (a) are exact for every polynomial of
// degree <= polyorder and (b) are themselves a polynomial of degree <= polyorder in the sample
// index (they lie in the span of the fit's basis), so (polyorder + 1)-th differences vanish.
TEST(SavitzkyGolayWeights, DefiningPropertiesForManyShapes) {
  for (int window = 3; window <= 25; window += 2) {
    for (int polyorder = 0; polyorder < std::min(window, 7); ++polyorder) {
      for (int derivative = 0; derivative <= polyorder; ++derivative) {
        for (int position = 0; position < window; ++position) {
          const double delta = 0.5;
          const auto w = weights_of(window, polyorder, derivative, position, delta);
          double scale = 0;
          for (double v : w) scale = std::max(scale, std::fabs(v));
          // (a) moments: sum_i w_i (x_i)^k = d^derivative/dx^derivative x^k at x = 0, x_i = (i - position) delta.
          for (int k = 0; k <= polyorder; ++k) {
            double moment = 0;
            double largest = 0;
            for (int i = 0; i < window; ++i) {
              const double term = w[static_cast<std::size_t>(i)] * std::pow((i - position) * delta, k);
              moment += term;
              largest = std::max(largest, std::fabs(term));
            }
            const double expected = k == derivative ? std::tgamma(derivative + 1) : 0.0;
            ASSERT_NEAR(moment, expected, 1e-12 * std::max(1.0, largest * window))
                << "window " << window << " order " << polyorder << " d" << derivative << " pos " << position
                << " moment " << k;
          }
          // (b) finite differences of order polyorder + 1 vanish.
          if (window > polyorder + 1) {
            std::vector<double> diff = w;
            for (int level = 0; level <= polyorder; ++level)
              for (std::size_t i = 0; i + 1 < diff.size() - static_cast<std::size_t>(level); ++i)
                diff[i] = diff[i + 1] - diff[i];
            for (std::size_t i = 0; i + static_cast<std::size_t>(polyorder) + 1 < diff.size(); ++i)
              ASSERT_NEAR(diff[i], 0.0, 1e-12 * scale * std::pow(2.0, polyorder + 1))
                  << "window " << window << " order " << polyorder << " d" << derivative << " pos " << position;
          }
        }
      }
    }
  }
}

TEST(SavitzkyGolayWeights, InvalidSpecsAreRefused) {
  const SavitzkyGolaySpec bad[] = {
      {6, 2, 0, -1, 1.0}, {5, 5, 0, -1, 1.0}, {5, 2, 3, -1, 1.0}, {5, 2, 0, 5, 1.0},
      {5, 2, 0, -1, 0.0}, {5, 2, 0, -1, NAN}, {0, 0, 0, -1, 1.0}, {5, -1, 0, -1, 1.0},
  };
  for (const auto& spec : bad) {
    auto result = savitzky_golay_weights(spec);
    ASSERT_TRUE(std::holds_alternative<Diagnostic>(result));
    EXPECT_EQ(std::get<Diagnostic>(result).code, "signal-invalid-options");
  }
}

// ---- estimates on signals ----------------------------------------------------------------------

double polynomial(const std::vector<double>& c, double t, int derivative) {
  double sum = 0;
  for (std::size_t k = static_cast<std::size_t>(derivative); k < c.size(); ++k) {
    double factor = 1;
    for (int j = 0; j < derivative; ++j) factor *= static_cast<double>(k) - j;
    sum += c[k] * factor * std::pow(t, static_cast<double>(k) - derivative);
  }
  return sum;
}

TEST(DerivativeEstimate, ExactOnPolynomialsAtEverySampleWhenShortened) {
  const double delta = 0.05;
  const std::vector<double> cubic = {0.7, -1.3, 2.1, 0.9};
  std::vector<double> y(40);
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = polynomial(cubic, static_cast<double>(i) * delta - 1.0, 0);
  for (const auto second : {DerivativeOptions::Second::repeated, DerivativeOptions::Second::direct}) {
    for (const int window : {5, 7, 9}) {
      DerivativeOptions o;
      o.window = window;
      o.polyorder = 3;
      o.second = second;
      o.edges = DerivativeOptions::Edges::shorten;
      EXPECT_EQ(samples_lost_each_side(2, o), 0);
      for (int order = 0; order <= 3; ++order) {
        const auto estimate = derivative_of(y, delta, order, o);
        for (std::size_t i = 0; i < y.size(); ++i) {
          const double exact = polynomial(cubic, static_cast<double>(i) * delta - 1.0, order);
          ASSERT_NEAR(estimate[i], exact, 1e-9 * (1 + std::fabs(exact)))
              << "window " << window << " order " << order << " sample " << i;
        }
      }
    }
  }
}

TEST(DerivativeEstimate, DropLosesTau0AtEachEnd) {
  std::vector<double> y(30, 1.0);
  DerivativeOptions o;  // 7 points, cubic, repeated
  for (int order = 1; order <= 3; ++order) {
    const auto estimate = derivative_of(y, 0.1, order, o);
    const int lost = samples_lost_each_side(order, o);
    EXPECT_EQ(lost, 3 * order);  // thesis 4-1: tau0 = 3 alpha Delta
    for (int i = 0; i < 30; ++i) {
      const bool kept = i >= lost && i < 30 - lost;
      EXPECT_EQ(std::isfinite(estimate[static_cast<std::size_t>(i)]), kept) << "order " << order << " sample " << i;
    }
  }
  o.second = DerivativeOptions::Second::direct;
  EXPECT_EQ(samples_lost_each_side(2, o), 3);
  EXPECT_EQ(samples_lost_each_side(0, o), 3);
  // A record shorter than the neighbourhood has no estimate at all, which is not an error.
  const auto short_one = derivative_of(std::vector<double>(5, 1.0), 0.1, 1, DerivativeOptions{});
  for (double v : short_one) EXPECT_TRUE(std::isnan(v));
}

TEST(DerivativeEstimate, InvalidRequestsAreRefused) {
  const std::vector<double> y(20, 0.0);
  DerivativeOptions direct;
  direct.second = DerivativeOptions::Second::direct;
  EXPECT_TRUE(std::holds_alternative<Diagnostic>(estimate_derivative(y, 0.1, 4, direct)));
  EXPECT_TRUE(std::holds_alternative<Diagnostic>(estimate_derivative(y, 0.1, -1, DerivativeOptions{})));
  EXPECT_TRUE(std::holds_alternative<Diagnostic>(estimate_derivative(y, 0.0, 1, DerivativeOptions{})));
  DerivativeOptions even;
  even.window = 6;
  EXPECT_FALSE(even.is_valid());
  EXPECT_EQ(samples_lost_each_side(1, even), -1);
  DerivativeOptions shorten;
  shorten.edges = DerivativeOptions::Edges::shorten;
  auto too_short = estimate_derivative(std::vector<double>(6, 0.0), 0.1, 1, shorten);
  ASSERT_TRUE(std::holds_alternative<Diagnostic>(too_short));
  EXPECT_EQ(std::get<Diagnostic>(too_short).code, "signal-too-short");
}

// On y = sin(w t) the 7-point cubic derivative (eq. 3-1.7) has the transfer function
// H(x) = (2/252)(58 sin x + 67 sin 2x - 22 sin 3x) = x - (6288 / 30240) x^5 + O(x^7), x = w Delta
// (the x^3 term cancels: the operator is exact for cubics), so its largest error is about
// w (6288 / 30240) x^4, fourth order in Delta; the repeated second derivative (eq. 3-1.8) has
// H(x)^2, so about w^2 2 (6288 / 30240) x^4.
TEST(DerivativeEstimate, SineErrorIsFourthOrderAsPredicted) {
  const double w = 4 * M_PI;
  const double c5 = 6288.0 / 30240.0;
  double previous_first = 0;
  for (const double delta : {0.02, 0.01, 0.005}) {
    const int n = static_cast<int>(std::lround(1.0 / delta)) + 1;
    std::vector<double> y(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) y[static_cast<std::size_t>(i)] = std::sin(w * i * delta);
    const DerivativeOptions o;
    const auto first = derivative_of(y, delta, 1, o);
    const auto second = derivative_of(y, delta, 2, o);
    double max_first = 0;
    double max_second = 0;
    for (int i = 0; i < n; ++i) {
      const double t = i * delta;
      if (std::isfinite(first[static_cast<std::size_t>(i)])) {
        max_first = std::max(max_first, std::fabs(first[static_cast<std::size_t>(i)] - w * std::cos(w * t)));
      }
      if (std::isfinite(second[static_cast<std::size_t>(i)])) {
        max_second = std::max(max_second, std::fabs(second[static_cast<std::size_t>(i)] + w * w * std::sin(w * t)));
      }
    }
    const double x = w * delta;
    EXPECT_NEAR(max_first / (w * c5 * std::pow(x, 4)), 1.0, 0.1) << "Delta = " << delta;
    EXPECT_NEAR(max_second / (w * w * 2 * c5 * std::pow(x, 4)), 1.0, 0.1) << "Delta = " << delta;
    if (previous_first > 0) {
      EXPECT_NEAR(previous_first / max_first, 16.0, 1.0) << "Delta = " << delta;
    }
    previous_first = max_first;
  }
}

// Thesis Appendix A, t = 0 .. 0.49: y rounded to two decimals, and the exact y' and y'' of the
// Runge-Kutta solution. The thesis differentiates the rounded y with eqs. 3-1.7 and 3-1.8 and
// plots the errors (Figure 4-1.8, Delta = 0.010): errors of both signs, and y'' errors far above
// 1.0. Rounding to 0.005 alone can move a 3-1.7 estimate by at most 0.005 * sum|w| (0.58 here)
// and a 3-1.8 estimate by 0.005 * sum|w| (51 here); truncation on this smooth record adds little,
// so the errors must stay within those bounds (with 10% for truncation) and be of both signs.
struct AppendixRow {
  double t, y, yd, ydd;
};
const AppendixRow kAppendixA[] = {
    {0.00, 0.00, 0.00, 0.0},      {0.01, 0.00, 0.67, 130.6},    {0.02, 0.02, 2.49, 226.6},
    {0.03, 0.05, 5.03, 272.8},    {0.04, 0.12, 7.70, 252.8},    {0.05, 0.21, 9.90, 184.1},
    {0.06, 0.31, 11.38, 112.3},   {0.07, 0.43, 12.24, 62.4},    {0.08, 0.56, 12.70, 32.0},
    {0.09, 0.69, 12.92, 12.2},    {0.10, 0.82, 12.96, -3.0},    {0.11, 0.94, 12.86, -16.9},
    {0.12, 1.07, 12.62, -30.6},   {0.13, 1.20, 12.24, -45.1},   {0.14, 1.32, 11.71, -61.0},
    {0.15, 1.43, 11.01, -79.1},   {0.16, 1.54, 10.12, -100.5},  {0.17, 1.63, 8.99, -126.6},
    {0.18, 1.71, 7.56, -159.8},   {0.19, 1.78, 5.75, -202.9},   {0.20, 1.83, 3.45, -258.9},
    {0.21, 1.85, 0.53, -325.0},   {0.22, 1.84, -3.12, -410.0},  {0.23, 1.78, -7.55, -466.7},
    {0.24, 1.68, -12.23, -459.5}, {0.25, 1.54, -16.46, -380.1}, {0.26, 1.36, -19.70, -265.8},
    {0.27, 1.15, -21.83, -164.4}, {0.28, 0.93, -23.10, -94.0},  {0.29, 0.69, -23.81, -48.8},
    {0.30, 0.45, -24.13, -18.0},  {0.31, 0.21, -24.19, 6.0},    {0.32, -0.03, -24.02, 27.8},
    {0.33, -0.27, -23.64, 49.2},  {0.34, -0.50, -23.03, 71.5},  {0.35, -0.73, -22.20, 95.4},
    {0.36, -0.95, -21.12, 121.7}, {0.37, -1.15, -19.75, 151.2}, {0.38, -1.34, -18.08, 185.0},
    {0.39, -1.51, -16.03, 224.5}, {0.40, -1.66, -13.56, 271.2}, {0.41, -1.78, -10.57, 326.9},
    {0.42, -1.87, -6.98, 391.5},  {0.43, -1.92, -2.73, 459.6},  {0.44, -1.92, 2.11, 491.9},
    {0.45, -1.88, 6.76, 420.3},   {0.46, -1.79, 10.20, 262.9},  {0.47, -1.68, 12.12, 131.0},
    {0.48, -1.55, 13.07, 66.8},   {0.49, -1.42, 13.61, 43.7},
};

TEST(DerivativeEstimate, ThesisAppendixARecord) {
  const double delta = 0.01;
  std::vector<double> y;
  for (const auto& row : kAppendixA) y.push_back(row.y);
  const DerivativeOptions thesis;  // eqs. 3-1.7 and 3-1.8
  const auto yd = derivative_of(y, delta, 1, thesis);
  const auto ydd = derivative_of(y, delta, 2, thesis);
  auto abs_sum = [](const std::vector<double>& w) {
    double s = 0;
    for (double v : w) s += std::fabs(v);
    return s;
  };
  const double rounding_first = 0.005 * abs_sum(thesis_stencil::first_7_cubic().weights(delta));
  const double rounding_second = 0.005 * abs_sum(thesis_stencil::second_7_repeated().weights(delta));
  double max_first = 0, max_second = 0;
  int positive = 0, negative = 0, compared = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    if (std::isfinite(yd[i])) {
      const double e = kAppendixA[i].yd - yd[i];  // eq. 4-1.4: observed - approximated
      max_first = std::max(max_first, std::fabs(e));
    }
    if (std::isfinite(ydd[i])) {
      const double e = kAppendixA[i].ydd - ydd[i];
      max_second = std::max(max_second, std::fabs(e));
      positive += e > 0;
      negative += e < 0;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 50 - 2 * 6);
  EXPECT_LE(max_first, 1.1 * rounding_first);
  EXPECT_LE(max_second, 1.1 * rounding_second);
  EXPECT_GT(max_second, 1.0);  // "an error of 1.0 is indeed very small when compared to ..." (4-1)
  EXPECT_GT(positive, compared / 4);
  EXPECT_GT(negative, compared / 4);
  // As percentages of the thesis' divisors (eq. 4-1.5: 24.2 for y', 492 for y''), for the report.
  RecordProperty("max_percent_error_first", std::to_string(100 * max_first / 24.2));
  RecordProperty("max_percent_error_second", std::to_string(100 * max_second / 492));
}

// The contract block evaluation relies on (signal_operator.hpp): given reach() samples beyond a
// block on each side, the operator's values on the block are bit for bit its values on the whole
// record, under every edge rule and way of taking higher derivatives.
TEST(MovingArcOperator, ReachGivesTheWholeRecordsValuesOnABlock) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, 0.01);
  std::vector<double> y(200);
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = std::sin(0.05 * static_cast<double>(i)) + noise(rng);
  const auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
  for (const auto edges : {DerivativeOptions::Edges::drop, DerivativeOptions::Edges::shorten})
    for (const auto second : {DerivativeOptions::Second::repeated, DerivativeOptions::Second::direct})
      for (int order = 0; order <= 3; ++order) {
        DerivativeOptions o;
        o.edges = edges;
        o.second = second;
        const MovingArcOperator op(order, o);
        EXPECT_EQ(op.samples_lost_each_side(), samples_lost_each_side(order, o));
        const auto whole = std::get<std::vector<double>>(op.apply(y, 0.1));
        const auto direct = derivative_of(y, 0.1, order, o);
        for (std::size_t i = 0; i < y.size(); ++i) EXPECT_TRUE(same(whole[i], direct[i])) << op.name() << ", sample " << i;
        const std::size_t reach = *op.reach();
        for (const std::size_t first : {std::size_t{0}, std::size_t{5}, std::size_t{40}, std::size_t{150}}) {
          const std::size_t last = std::min(y.size(), first + 30);
          const std::size_t from = first > reach ? first - reach : 0, to = std::min(y.size(), last + reach);
          const auto part = std::get<std::vector<double>>(op.apply(std::span(y).subspan(from, to - from), 0.1));
          for (std::size_t i = first; i < last; ++i) EXPECT_TRUE(same(whole[i], part[i - from])) << op.name() << ", sample " << i;
        }
      }
}

}  // namespace
}  // namespace sidc
