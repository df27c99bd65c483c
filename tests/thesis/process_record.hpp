// A record of the thesis' chemical process (section 4-2), made here because the original is
// proprietary: the linear system of eq. 4-2.5 (the thesis' own fitted coefficients, time in
// minutes) driven by a smooth input, solved by fourth-order Runge-Kutta (the thesis' solver) on a
// fine step, sampled every 0.75 minutes for 85.5 minutes (115 samples, as Figs. 4-2.2 to 4-2.7),
// with Gaussian measurement noise from a fixed seed. Used by tests/thesis/process_4_2_test.cpp
// and by write_process_record.cpp, which writes examples/thesis-4-2/process_record.csv.
//
// process_held_record() is the same process driven as a test engineer would drive it: the input
// set to a new level, held until the next change, each change at a sample instant (input x held).
// It writes examples/thesis-4-2/process_held_record.csv.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace sidc::thesis {

// eq. 4-2.5: y1' = a1 y1 + a2 y2 + a3 x + a4, y2' = a5 y1 + a6 y2 + a7 x + a8.
inline constexpr std::array<double, 8> kProcess{-0.169520, -0.150604, -0.013276, 7.607216,
                                                -0.166036, -0.170566, -0.001100, 8.578805};

inline double process_input(double t) { return 100 + 30 * std::sin(0.25 * t) + 15 * std::sin(0.07 * t + 1); }

struct ProcessRecord {
  std::vector<double> t, x, y1, y2;
};

inline ProcessRecord process_record(double noise = 0.05, unsigned seed = 4252) {
  const auto& a = kProcess;
  auto slope = [&](double t, double y1, double y2) {
    const double x = process_input(t);
    return std::array<double, 2>{a[0] * y1 + a[1] * y2 + a[2] * x + a[3], a[4] * y1 + a[5] * y2 + a[6] * x + a[7]};
  };
  ProcessRecord r;
  std::mt19937 rng(seed);
  std::normal_distribution<double> error(0.0, noise);
  double y1 = 0.0, y2 = 50.0;  // eq. 4-2.1: y1(0) = 0, y2(0) = 50
  const double sample = 0.75, h = sample / 150;
  for (int k = 0; k <= 114; ++k) {
    const double t = k * sample;
    r.t.push_back(t);
    r.x.push_back(process_input(t));
    r.y1.push_back(y1 + error(rng));
    r.y2.push_back(y2 + error(rng));
    for (int s = 0; s < 150; ++s) {  // classic RK4 between samples
      const double ts = t + s * h;
      const auto k1 = slope(ts, y1, y2);
      const auto k2 = slope(ts + h / 2, y1 + h / 2 * k1[0], y2 + h / 2 * k1[1]);
      const auto k3 = slope(ts + h / 2, y1 + h / 2 * k2[0], y2 + h / 2 * k2[1]);
      const auto k4 = slope(ts + h, y1 + h * k3[0], y2 + h * k3[1]);
      y1 += h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]);
      y2 += h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]);
    }
  }
  return r;
}

// The held input: one level per sample interval, x[k] holding on [t_k, t_k+1). A level is drawn
// uniformly in [70, 130] and rounded to 0.1 (a set point as dialled), and holds for 1 to 4 sample
// intervals (equally likely) before the next, different, level is drawn. The draws use the raw
// output of mt19937, which the standard fixes, not a distribution, whose algorithm each library
// chooses.
inline std::vector<double> process_held_input(std::size_t samples, unsigned seed = 4253) {
  std::mt19937 rng(seed);
  std::vector<double> x;
  while (x.size() < samples) {
    double level;
    do {  // a new level: drawn again in the rare case that it rounds to the one it replaces
      const double u = static_cast<double>(rng()) / 4294967296.0;  // [0, 1)
      level = std::round(10 * (70 + 60 * u)) / 10;
    } while (!x.empty() && level == x.back());
    const auto intervals = static_cast<std::uint32_t>(1 + rng() % 4);
    for (std::uint32_t i = 0; i < intervals && x.size() < samples; ++i) x.push_back(level);
  }
  return x;
}

// eq. 4-2.5 driven by the held input: RK4 on a step of 0.005 min (150 steps per 0.75 min sample
// interval), with x constant on each interval, so no step straddles a change of level and RK4
// keeps its order; 115 samples; the noise of process_record() (standard deviation 0.05 on y1 and
// y2, seed 4252, drawn in the same order, so both records carry the same noise sequence).
inline ProcessRecord process_held_record(double noise = 0.05, unsigned seed = 4252, unsigned input_seed = 4253) {
  const auto& a = kProcess;
  auto slope = [&](double x, double y1, double y2) {
    return std::array<double, 2>{a[0] * y1 + a[1] * y2 + a[2] * x + a[3], a[4] * y1 + a[5] * y2 + a[6] * x + a[7]};
  };
  ProcessRecord r;
  std::mt19937 rng(seed);
  std::normal_distribution<double> error(0.0, noise);
  const std::size_t samples = 115;
  const std::vector<double> input = process_held_input(samples, input_seed);
  double y1 = 0.0, y2 = 50.0;  // eq. 4-2.1: y1(0) = 0, y2(0) = 50
  const double sample = 0.75, h = sample / 150;
  for (std::size_t k = 0; k < samples; ++k) {
    const double x = input[k];
    r.t.push_back(static_cast<double>(k) * sample);
    r.x.push_back(x);
    r.y1.push_back(y1 + error(rng));
    r.y2.push_back(y2 + error(rng));
    for (int s = 0; s < 150; ++s) {  // classic RK4 between samples, x held at input[k]
      const auto k1 = slope(x, y1, y2);
      const auto k2 = slope(x, y1 + h / 2 * k1[0], y2 + h / 2 * k1[1]);
      const auto k3 = slope(x, y1 + h / 2 * k2[0], y2 + h / 2 * k2[1]);
      const auto k4 = slope(x, y1 + h * k3[0], y2 + h * k3[1]);
      y1 += h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]);
      y2 += h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]);
    }
  }
  return r;
}

// A record as the example's CSV file holds it: t to 0.01 min, the signals to 1e-6.
inline std::string process_record_csv(const ProcessRecord& r) {
  std::string text = "t,x,y1,y2\n";
  char line[128];
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    std::snprintf(line, sizeof line, "%.2f,%.6f,%.6f,%.6f\n", r.t[k], r.x[k], r.y1[k], r.y2[k]);
    text += line;
  }
  return text;
}

}  // namespace sidc::thesis
