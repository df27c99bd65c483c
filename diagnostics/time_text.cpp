#include "diagnostics/time_text.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace sidc {

std::string time_text(double t, double step, int digits) {
  if (std::isfinite(t) && step > 0 && std::isfinite(step) && t != 0) {
    const double ratio = std::abs(t) / step;  // samples from 0: the digits that tell them apart
    if (ratio >= std::pow(10.0, digits)) digits = std::min(17, static_cast<int>(std::ceil(std::log10(ratio))) + 1);
  }
  return fmt::format("{:.{}g}", t, digits);
}

}  // namespace sidc
