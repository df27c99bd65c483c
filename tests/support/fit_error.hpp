// Test support for the tests that fit known-truth records in-process (tests/runtime): the largest
// relative error of the fitted parameters, the measure of issue 13's targets and of
// bench/fidelity. A compile or fit failure fails the test and returns a huge error.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <string>

#include "compiler/pipeline.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc::testing {

// max over the parameters named in `truth` of |estimate / truth - 1|; the others are not judged.
inline double largest_relative_error(const std::string& text, const SampledRecord& record, const std::map<std::string, double>& truth,
                                     const FitOptions& options = {}) {
  const CompileResult c = compile(std::make_shared<const SourceFile>("m.sid", text), {});
  EXPECT_TRUE(c.ok()) << c.diagnostics.render_all();
  if (!c.ok()) return 1e9;
  auto fitted = fit(*c.integrated, {record}, options);
  EXPECT_TRUE(std::holds_alternative<FitSummary>(fitted)) << std::get<Diagnostic>(fitted).message;
  if (!std::holds_alternative<FitSummary>(fitted)) return 1e9;
  double worst = 0;
  for (const auto& g : std::get<FitSummary>(fitted).groups)
    for (const auto& p : g.summary.parameters)
      if (auto t = truth.find(p.name); t != truth.end()) worst = std::max(worst, std::abs(p.value / t->second - 1));
  return worst;
}

}  // namespace sidc::testing
