// A record made in a test from functions of time: n samples t = 0, step, 2 step, ..., each named
// signal its function's values there (path "synthetic"). Header-only.
#pragma once

#include <cstddef>
#include <functional>
#include <map>
#include <string>

#include "runtime/records/sampled_record.hpp"

namespace sidc::testing {

inline SampledRecord synthetic_record(std::size_t n, double step, const std::map<std::string, std::function<double(double)>>& signals) {
  SampledRecord r;
  r.path = "synthetic";
  r.step = step;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = step * static_cast<double>(k);
    r.time.push_back(t);
    for (const auto& [name, value] : signals) r.signals[name].push_back(value(t));
  }
  return r;
}

}  // namespace sidc::testing
