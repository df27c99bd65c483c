// A record of the thesis' chemical process (section 4-2), made here because the original is
// proprietary: the linear system of eq. 4-2.5 (the thesis' own fitted coefficients, time in
// minutes) driven by a smooth input, solved by fourth-order Runge-Kutta (the thesis' solver) on a
// fine step, sampled every 0.75 minutes for 85.5 minutes (115 samples, as Figs. 4-2.2 to 4-2.7),
// with Gaussian measurement noise from a fixed seed. Used by tests/thesis/process_4_2_test.cpp
// and by write_process_record.cpp, which writes examples/thesis-4-2/process_record.csv.
#pragma once

#include <array>
#include <cmath>
#include <random>
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

}  // namespace sidc::thesis
