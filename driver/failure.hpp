// What a failed step of a driver leaves (fit_run.hpp, select_run.hpp): the Diagnostics to print, and
// whether a setting was at fault (exit code 2 on the command line: docs/cli.md) rather than the
// model or a record (exit code 1).
#pragma once

#include <utility>
#include <vector>

#include "diagnostics/diagnostic.hpp"

namespace sidc::driver {

struct Failure {
  std::vector<Diagnostic> diagnostics;
  bool bad_setting = false;
};

inline Failure failure(Diagnostic d, bool bad_setting = false) { return Failure{{std::move(d)}, bad_setting}; }

}  // namespace sidc::driver
