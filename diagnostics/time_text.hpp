// A time as sidc's messages and reports print it. With `digits` significant digits, as everywhere,
// unless that many cannot tell neighbouring samples `step` apart: a record stamped in Unix seconds
// (t = 1732780829.99 at Delta = 0.01) would print 1.733e+09 for every sample and every event, so it
// gets the digits the step needs (1732780829.99), at most 17.
#pragma once

#include <string>

namespace sidc {

std::string time_text(double t, double step, int digits);

}  // namespace sidc
