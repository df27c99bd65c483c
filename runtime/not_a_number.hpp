// The quiet NaN that marks a value not computed: a sample no guard holds at, a run's samples after
// it stopped, a criterion a subset could not be given. One name for every file of runtime/.
#pragma once

#include <limits>

namespace sidc {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace sidc
