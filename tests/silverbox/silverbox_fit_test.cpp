// The Silverbox electronic Duffing oscillator (examples/silverbox), fitted by the sidc binary and
// checked against what the record itself says about the circuit, measured here without sidc.
//
// Relies on: the sidc binary (SIDC_BINARY), examples/silverbox with SNLS80mV.csv and the models
// derivative_form.sid and integrated_once.sid (SIDC_SILVERBOX_EXAMPLE_DIR), a writable scratch
// folder (SIDC_SILVERBOX_WORK_DIR), and the fit.json format of `sidc fit --out`.
// Guarantees: the sidc commands a user runs (`sidc compile X.sid`, `sidc fit X.sidc.json --out D`)
// run once per test program on copies in the scratch folder; the source tree is never written.
//
// What is checked, and why it can fail for the right reasons: the model is
//   m*y'' + d*y' + k1*y + k3*y^3 + c0 = u,
// so the linear part resonates at f_n = sqrt(k1/m)/(2 pi) with damping ratio d/(2 sqrt(k1 m)).
// The record shows its resonance directly: the phase of the cross-spectral estimate
// H(f) = S_uy/S_uu passes -90 degrees at f_n and -45/-135 degrees at f_n (sqrt(1 + zeta^2) -/+ zeta),
// exactly for a second-order system. At low amplitude (the start of the arrow section, output
// s.d. 14 mV) the cubic is negligible; in the multisine section (output s.d. 55 mV) the
// hardening cubic raises the resonance to that of the equivalent linear stiffness
// k1 + 3*k3*E[y^2] (statistical linearisation of a cubic with Gaussian y). Neither spectral
// estimate uses sidc, and no expected value below is a number sidc printed. With the thesis'
// default 7-point cubic arc in derivative_form.sid (f_n = 64.6 Hz, 6% low) every test here fails.
#include <cmath>
#include <complex>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/shell.hpp"
#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;
using sidc::testing::read_text;
using sidc::testing::shell_quoted;
using nlohmann::json;

constexpr double kStep = 0.0016384;  // 2^14/1e7 s, the exact sampling step
constexpr double kPi = std::numbers::pi;

// The benchmark's sections (0-based, half open), examples/silverbox/README.md.
constexpr std::size_t kLowAmplitudeFirst = 100, kLowAmplitudeLast = 10100;  // start of the arrow
constexpr std::size_t kSectionFirst = 40650, kSectionLast = 105712;         // the models' section

// V1 and V2 of SNLS80mV.csv: a quoted header, then "v1,v2," per line.
struct Record {
  std::vector<double> u, y;
};

Record read_record(const fs::path& path) {
  Record r;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // "V1","V2",
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::istringstream fields(line);
    std::string a, b;
    std::getline(fields, a, ',');
    std::getline(fields, b, ',');
    r.u.push_back(std::stod(a));
    r.y.push_back(std::stod(b));
  }
  return r;
}

double standard_deviation(const std::vector<double>& x, std::size_t first, std::size_t last) {
  double mean = 0.0;
  for (std::size_t i = first; i < last; ++i) mean += x[i];
  mean /= static_cast<double>(last - first);
  double sum = 0.0;
  for (std::size_t i = first; i < last; ++i) sum += (x[i] - mean) * (x[i] - mean);
  return std::sqrt(sum / static_cast<double>(last - first));
}

// Where the phase of H = S_uy/S_uu crosses -45, -90 and -135 degrees between 50 and 90 Hz
// (in this record the phase is above -10 degrees at 50 Hz and below -160 degrees at 90 Hz).
// Welch's estimate: segments of 2048 samples, half overlapping, mean removed, Hann window; the
// DFT is evaluated only at the bins of the band. Crossings are interpolated linearly in phase.
struct PhaseCrossings {
  double f45 = NAN, f90 = NAN, f135 = NAN;
  double damping_ratio() const { return (f135 - f45) / (2.0 * f90); }
};

PhaseCrossings phase_crossings(const Record& r, std::size_t first, std::size_t last) {
  constexpr std::size_t kSegment = 2048;
  const double fs = 1.0 / kStep;
  const auto bin_low = static_cast<std::size_t>(50.0 * kSegment / fs);
  const auto bin_high = static_cast<std::size_t>(90.0 * kSegment / fs) + 1;
  std::vector<double> window(kSegment);
  for (std::size_t i = 0; i < kSegment; ++i) window[i] = 0.5 - 0.5 * std::cos(2.0 * kPi * i / kSegment);
  std::vector<std::complex<double>> suy(bin_high - bin_low + 1);
  std::vector<double> suu(bin_high - bin_low + 1);
  std::vector<double> su(kSegment), sy(kSegment);
  for (std::size_t start = first; start + kSegment <= last; start += kSegment / 2) {
    double mu = 0.0, my = 0.0;
    for (std::size_t i = 0; i < kSegment; ++i) {
      mu += r.u[start + i];
      my += r.y[start + i];
    }
    mu /= kSegment;
    my /= kSegment;
    for (std::size_t i = 0; i < kSegment; ++i) {
      su[i] = window[i] * (r.u[start + i] - mu);
      sy[i] = window[i] * (r.y[start + i] - my);
    }
    for (std::size_t k = bin_low; k <= bin_high; ++k) {
      // Twiddles by rotation: exact enough over 2048 steps for a phase read to a tenth of a degree.
      const std::complex<double> rotation = std::polar(1.0, -2.0 * kPi * k / kSegment);
      std::complex<double> twiddle = 1.0, U = 0.0, Y = 0.0;
      for (std::size_t i = 0; i < kSegment; ++i) {
        U += su[i] * twiddle;
        Y += sy[i] * twiddle;
        twiddle *= rotation;
      }
      suy[k - bin_low] += std::conj(U) * Y;
      suu[k - bin_low] += std::norm(U);
    }
  }
  PhaseCrossings c;
  double previous_phase = 0.0;
  for (std::size_t k = bin_low; k <= bin_high; ++k) {
    // Unwrapped: the phase of this system falls monotonically from 0 towards -180 degrees.
    double phase = std::arg(suy[k - bin_low] / suu[k - bin_low]) * 180.0 / kPi;
    while (k > bin_low && phase > previous_phase + 180.0) phase -= 360.0;
    while (k > bin_low && phase < previous_phase - 180.0) phase += 360.0;
    if (k > bin_low) {
      const double f_prev = (k - 1) * fs / kSegment, f = k * fs / kSegment;
      for (auto [target, slot] : {std::pair{-45.0, &c.f45}, std::pair{-90.0, &c.f90}, std::pair{-135.0, &c.f135}})
        if (std::isnan(*slot) && previous_phase >= target && phase < target)
          *slot = f_prev + (f - f_prev) * (target - previous_phase) / (phase - previous_phase);
    }
    previous_phase = phase;
  }
  return c;
}

struct Fit {
  json group;
  double estimate(const std::string& name) const {
    for (const json& p : group.at("parameters"))
      if (p.at("name") == name) return p.at("estimate").get<double>();
    ADD_FAILURE() << "no parameter " << name << " in fit.json";
    return NAN;
  }
  double lower95(const std::string& name) const {
    for (const json& p : group.at("parameters"))
      if (p.at("name") == name) return p.at("ci95").at(0).get<double>();
    ADD_FAILURE() << "no parameter " << name << " in fit.json";
    return NAN;
  }
  double statistic(const std::string& name) const { return group.at("statistics").at(name).get<double>(); }
  double natural_frequency() const { return std::sqrt(estimate("k1") / estimate("m")) / (2.0 * kPi); }
  double damping_ratio() const { return estimate("d") / (2.0 * std::sqrt(estimate("k1") * estimate("m"))); }
  // The resonance of the equivalent linear stiffness k1 + 3*k3*E[y^2] at output s.d. sigma.
  double equivalent_frequency(double sigma) const {
    return std::sqrt((estimate("k1") + 3.0 * estimate("k3") * sigma * sigma) / estimate("m")) / (2.0 * kPi);
  }
};

// Everything the tests read, computed once for the program: two sidc fits and the spectra.
class Silverbox : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const fs::path examples(SIDC_SILVERBOX_EXAMPLE_DIR);
    work_ = fs::path(SIDC_SILVERBOX_WORK_DIR);
    fs::remove_all(work_);
    fs::create_directories(work_);
    for (const char* file : {"SNLS80mV.csv", "derivative_form.sid", "integrated_once.sid"})
      fs::copy_file(examples / file, work_ / file);
    derivative_ = new Fit{fit("derivative_form")};
    integrated_ = new Fit{fit("integrated_once")};
    const Record record = read_record(work_ / "SNLS80mV.csv");
    low_ = phase_crossings(record, kLowAmplitudeFirst, kLowAmplitudeLast);
    section_ = phase_crossings(record, kSectionFirst, kSectionLast);
    section_output_sd_ = standard_deviation(record.y, kSectionFirst, kSectionLast);
    std::cout << "record: " << record.u.size() << " rows; low amplitude [100, 10100): phase -90 deg at " << low_.f90
              << " Hz, zeta from -45/-135 deg " << low_.damping_ratio() << "; section [40650, 105712): -90 deg at "
              << section_.f90 << " Hz, output s.d. " << section_output_sd_ << " V\n";
    for (const auto& [label, f] : {std::pair{"derivative form", derivative_}, std::pair{"integrated once", integrated_}})
      if (!f->group.is_null())
        std::cout << label << ": f_n " << f->natural_frequency() << " Hz, zeta " << f->damping_ratio()
                  << ", resonance at the section's amplitude " << f->equivalent_frequency(section_output_sd_)
                  << " Hz, k1/m " << f->estimate("k1") / f->estimate("m")
                  << ", k3/m " << f->estimate("k3") / f->estimate("m") << "\n";
  }

  static void TearDownTestSuite() {
    delete derivative_;
    delete integrated_;
  }

  void SetUp() override {
    ASSERT_FALSE(derivative_->group.is_null()) << "the derivative-form fit failed (see the output above)";
    ASSERT_FALSE(integrated_->group.is_null()) << "the integrated-form fit failed (see the output above)";
    ASSERT_FALSE(std::isnan(low_.f90) || std::isnan(low_.f45) || std::isnan(low_.f135) || std::isnan(section_.f90))
        << "no phase crossing found in the record";
  }

  // `sidc compile <model>.sid && sidc fit <model>.sidc.json --out out.<model>`; a null group on failure.
  static json fit(const std::string& model) {
    const std::string binary = shell_quoted(fs::path(SIDC_BINARY));
    const fs::path log = work_ / (model + ".log");
    const std::string command = binary + " compile " + shell_quoted(work_ / (model + ".sid")) + " && " + binary + " fit " +
                                shell_quoted(work_ / (model + ".sidc.json")) + " --out " + shell_quoted(work_ / ("out." + model));
    if (std::system(("(" + command + ") >" + shell_quoted(log) + " 2>&1").c_str()) != 0) {
      std::cout << "command failed: " << command << "\n" << read_text(log);
      return json();
    }
    return json::parse(read_text(work_ / ("out." + model) / "fit.json")).at("groups").at(0);
  }

  static inline fs::path work_;
  static inline Fit* derivative_ = nullptr;
  static inline Fit* integrated_ = nullptr;
  static inline PhaseCrossings low_, section_;
  static inline double section_output_sd_ = NAN;
};

// The equation explains the record: R^2 of the known side u, full rank, every coefficient of the
// linear part positive (a passive, stable oscillator), and a cubic whose whole 95% interval is
// positive: with `+ k3*y^3` on the left of `= u`, k3 > 0 is a restoring force that grows faster
// than linearly, a hardening spring.
TEST_F(Silverbox, DerivativeFormFitsWithHardeningCubic) {
  const Fit& f = *derivative_;
  EXPECT_GT(f.statistic("r_squared"), 0.99);
  EXPECT_EQ(f.statistic("rank"), f.statistic("p"));
  EXPECT_GT(f.estimate("m"), 0.0);
  EXPECT_GT(f.estimate("d"), 0.0);
  EXPECT_GT(f.estimate("k1"), 0.0);
  EXPECT_GT(f.lower95("k3"), 0.0) << "the cubic should be hardening, and clearly so";
}

// sqrt(k1/m)/(2 pi) is the small-amplitude resonance the record shows: within 1% of where the
// measured phase crosses -90 degrees at low amplitude.
TEST_F(Silverbox, LinearNaturalFrequencyIsTheLowAmplitudeResonance) {
  EXPECT_NEAR(derivative_->natural_frequency(), low_.f90, 0.01 * low_.f90);
}

// The damping ratio agrees with the measured -45/-135 degree points within 10%.
TEST_F(Silverbox, DampingRatioMatchesThePhaseOfTheRecord) {
  EXPECT_NEAR(derivative_->damping_ratio(), low_.damping_ratio(), 0.10 * low_.damping_ratio());
}

// The fitted cubic predicts how far the resonance moves up at the multisine's amplitude: the
// equivalent linear resonance lands within 1% of the measured one, and the predicted shift
// (about 1 Hz) within 0.3 Hz of the measured shift. Without the cubic the shift would be zero.
TEST_F(Silverbox, CubicPredictsTheResonanceShiftWithAmplitude) {
  const double predicted = derivative_->equivalent_frequency(section_output_sd_);
  EXPECT_NEAR(predicted, section_.f90, 0.01 * section_.f90);
  EXPECT_GT(section_.f90, low_.f90) << "the record itself should show a hardening resonance";
  EXPECT_NEAR(predicted - derivative_->natural_frequency(), section_.f90 - low_.f90, 0.3);
}

// The integrated form (eq. 2-1.4 once: only y' left to estimate) tells the same story. Its
// parameters differ from the derivative form's by more than either's interval
// (examples/silverbox/README.md, "Which form gives consistent parameters"): integration weights
// the slow part of the equation error, which the intervals do not describe. What it gets right
// is asserted here, with the measured differences in brackets: damping ratio within 3% (0.4%),
// stiffness per unit mass k1/m within 3% (1.5%), a hardening cubic, and k3/m within 40% (it
// overestimates by about 25%).
TEST_F(Silverbox, IntegratedFormAgreesWithDerivativeForm) {
  const Fit& d = *derivative_;
  const Fit& i = *integrated_;
  EXPECT_GT(i.statistic("r_squared"), 0.99);
  EXPECT_NEAR(i.damping_ratio(), d.damping_ratio(), 0.03 * d.damping_ratio());
  const double k1m_d = d.estimate("k1") / d.estimate("m"), k1m_i = i.estimate("k1") / i.estimate("m");
  EXPECT_NEAR(k1m_i, k1m_d, 0.03 * k1m_d);
  EXPECT_GT(i.lower95("k3"), 0.0);
  const double k3m_d = d.estimate("k3") / d.estimate("m"), k3m_i = i.estimate("k3") / i.estimate("m");
  EXPECT_NEAR(k3m_i, k3m_d, 0.40 * k3m_d);
}

// Issue 15's Silverbox target: refined by the output error on the train/validation section (the
// fit window), the equations solved over the benchmark's test section [105712, 127400) from the
// record's state there (the first 50 samples left out, as the benchmark does) reproduce the
// measured output to at most 0.5 mV RMS (measured 0.43 mV), where the equation-error estimate
// misses by more (0.89 mV): the test can fail either way.
std::string exact(double v) {
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

double test_section_rms(const fs::path& work, const fs::path& fit_json, const std::string& name) {
  constexpr std::size_t kTestFirst = 105712, kTestLast = 127400, kSettle = 50;
  const std::string binary = shell_quoted(fs::path(SIDC_BINARY));
  const fs::path out = work / (name + ".test.csv"), log = work / (name + ".test.log");
  const std::string command = binary + " simulate " + shell_quoted(work / "derivative_form.sid") + " --params " + shell_quoted(fit_json) +
                              " --t0 " + exact(kTestFirst * kStep) + " --t1 " + exact((kTestLast - 1) * kStep) +
                              " --substeps 8 -o " + shell_quoted(out);
  if (std::system(("(" + command + ") >" + shell_quoted(log) + " 2>&1").c_str()) != 0) {
    ADD_FAILURE() << "command failed: " << command << "\n" << read_text(log);
    return NAN;
  }
  const Record record = read_record(work / "SNLS80mV.csv");
  std::istringstream lines(read_text(out));
  std::string line;
  std::getline(lines, line);  // t,V2
  double squares = 0;
  std::size_t k = 0, n = 0;
  for (; std::getline(lines, line); ++k) {
    if (k < kSettle || line.empty()) continue;
    // Each row compared with the record's sample at its own time: t = index * step.
    const auto index = static_cast<std::size_t>(std::llround(std::stod(line.substr(0, line.find(','))) / kStep));
    const double simulated = std::stod(line.substr(line.find(',') + 1));
    if (index >= record.y.size()) break;
    squares += std::pow(simulated - record.y[index], 2);
    ++n;
  }
  EXPECT_GT(n, 20000u) << "the simulation did not cover the test section";
  return n ? std::sqrt(squares / static_cast<double>(n)) : NAN;
}

TEST_F(Silverbox, RefinedFitSimulatesTheTestSectionWithinHalfAMillivolt) {
  const std::string binary = shell_quoted(fs::path(SIDC_BINARY));
  const fs::path log = work_ / "refined.log";
  const std::string command = binary + " fit " + shell_quoted(work_ / "derivative_form.sidc.json") + " --refine --no-validate --out " +
                              shell_quoted(work_ / "out.refined");
  ASSERT_EQ(std::system(("(" + command + ") >" + shell_quoted(log) + " 2>&1").c_str()), 0) << read_text(log);
  const json refined = json::parse(read_text(work_ / "out.refined" / "fit.json")).at("refinement");
  ASSERT_EQ(refined.at("status"), "converged") << refined.dump(1);
  const double equation_error = test_section_rms(work_, work_ / "out.derivative_form" / "fit.json", "equation_error");
  const double output_error = test_section_rms(work_, work_ / "out.refined" / "fit.json", "refined");
  std::cout << "test section RMS error: equation error " << 1000 * equation_error << " mV, refined " << 1000 * output_error << " mV\n";
  EXPECT_LT(output_error, 0.5e-3);
  EXPECT_GT(equation_error, 0.5e-3);
}

}  // namespace
