// Test support for the tests that simulate compiled models in-process (tests/runtime): a model
// compiled to its normalized form, its explicit form, a uniform time grid, and a record made by
// simulating a model, with noise.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <variant>
#include <vector>

#include "compiler/explicit_form_pass.hpp"
#include "compiler/pipeline.hpp"
#include "runtime/simulate/simulate.hpp"

namespace sidc::testing {

// The normalized model of `text` (file name test.sid); a compile error fails the test.
inline ir::Model normalized(const std::string& text) {
  CompileResult r = compile(std::make_shared<const SourceFile>("test.sid", text), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return *r.normalized;
}

// The model's explicit form; a failure fails the test (and throws bad_variant_access).
inline ExplicitForm form_of(const ir::Model& m) {
  auto f = explicit_form(m);
  EXPECT_TRUE(std::holds_alternative<ExplicitForm>(f)) << render(std::get<Diagnostic>(f));
  return std::get<ExplicitForm>(f);
}

// t0, t0 + step, ..., t1 (the number of steps rounded, so t1 is reached without drift).
inline std::vector<double> grid(double t0, double t1, double step) {
  std::vector<double> t;
  const auto n = static_cast<std::size_t>(std::llround((t1 - t0) / step));
  for (std::size_t i = 0; i <= n; ++i) t.push_back(t0 + static_cast<double>(i) * step);
  return t;
}

// Gaussian noise of `share` times the standard deviation of `y` added to every sample of `y`
// (the known-truth records' convention: noise as a share of the signal's spread).
inline void add_noise(std::vector<double>& y, double share, std::mt19937& engine) {
  double mean = 0, squares = 0;
  for (double v : y) mean += v;
  mean /= static_cast<double>(y.size());
  for (double v : y) squares += (v - mean) * (v - mean);
  std::normal_distribution<double> noise(0.0, share * std::sqrt(squares / static_cast<double>(y.size())));
  for (double& v : y) v += noise(engine);
}

// The outputs of `m` solved with `o` (its grid uniform) as a record named `path`, each output with
// Gaussian noise of `share` of its standard deviation (add_noise, one engine seeded `seed`, the
// outputs in the explicit form's order); inputs are the caller's to add. A failed run fails the test.
inline SampledRecord simulated_record(const ir::Model& m, const ExplicitForm& f, const SimulateOptions& o, const std::string& path,
                                      double share, unsigned seed) {
  auto run = simulate(m, f, o);
  EXPECT_TRUE(std::holds_alternative<SimulationSummary>(run)) << render(std::get<Diagnostic>(run));
  SampledRecord record;
  record.path = path;
  record.step = o.time.size() > 1 ? o.time[1] - o.time[0] : 0.0;
  record.time = o.time;
  if (!std::holds_alternative<SimulationSummary>(run)) return record;
  std::mt19937 engine(seed);
  for (std::size_t j = 0; j < f.outputs.size(); ++j) {
    std::vector<double> y = std::get<SimulationSummary>(run).outputs[j];
    if (share > 0) add_noise(y, share, engine);
    record.signals[f.outputs[j].name] = std::move(y);
  }
  return record;
}

}  // namespace sidc::testing
