// sidc's exit codes (docs/cli.md): scripts can tell a bad model from a bad command line from a bug.
#pragma once

#include <iostream>
#include <string>

#include "driver/failure.hpp"

namespace sidc::exit_code {
inline constexpr int success = 0;
inline constexpr int user_error = 1;      // the model, a data file or a compiled model is wrong: see stderr
inline constexpr int usage_error = 2;     // the command line is wrong: see `sidc --help`
inline constexpr int internal_error = 3;  // a bug in sidc: please report it with the input
}  // namespace sidc::exit_code

namespace sidc {
// Every command ends a failure the same way: the rendered message on stderr, then its exit code.
inline int fail(const std::string& message, int code) {
  std::cerr << message << "\n";
  return code;
}
// A failed step of the driver (driver/failure.hpp) the same way: each diagnostic, then its code.
inline int fail(const driver::Failure& failure) {
  for (const auto& d : failure.diagnostics) std::cerr << render(d) << "\n";
  return failure.bad_setting ? exit_code::usage_error : exit_code::user_error;
}
}  // namespace sidc
