// sidc: determination of parameters and operations in dynamic systems (Bernhart, 1964).
// This file only dispatches to the subcommands; each lives in its own *_command.cpp.
#include <CLI/CLI.hpp>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>

#include "cli/compile_command.hpp"
#include "cli/exit_codes.hpp"
#include "cli/fit_command.hpp"
#include "cli/simulate_command.hpp"
#include "cli/select_command.hpp"
#include "diagnostics/cli_catalogue.hpp"

namespace {

// Output that never arrived is a failure, not a success: a full disk (`> /dev/full`) or a reader
// that went away (`| head`) ends the run with exit 1 and says so. SIGPIPE is ignored (in main) so
// that a closed pipe is a write error here rather than a silent death by signal.
int with_stdout_checked(int code) {
  errno = 0;  // the first failing flush sets it; a later successful call leaves it
  std::cout.flush();
  const bool flushed = std::fflush(stdout) == 0;
  const int error = errno;
  if (flushed && !std::ferror(stdout) && !std::cout.fail()) return code;
  std::cerr << sidc::render(sidc::cli_diag::cannot_write_stdout(error ? std::strerror(error) : "a write failed")) << "\n";
  return code == sidc::exit_code::success ? sidc::exit_code::user_error : code;
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGPIPE, SIG_IGN);
  CLI::App app{"sidc: identify the parameters and operations of dynamic systems from recorded data\n"
               "(the method of W. D. Bernhart, 1964). Main path: sidc compile model.sid && sidc fit"};
  app.set_version_flag("--version", std::string("sidc ") + SIDC_VERSION);
  app.require_subcommand(1);
  int exit_status = sidc::exit_code::success;
  try {
    sidc::add_compile_command(app, exit_status);
    sidc::add_fit_command(app, exit_status);
    sidc::add_simulate_command(app, exit_status);
    sidc::add_select_command(app, exit_status);
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      const int code = app.exit(e);  // prints help, version or the usage error
      return with_stdout_checked(code == 0 ? sidc::exit_code::success : sidc::exit_code::usage_error);
    }
  } catch (const std::exception& e) {
    std::cerr << "internal error: " << e.what() << "\nThis is a bug in sidc; please report it with the input that caused it.\n";
    return sidc::exit_code::internal_error;
  }
  return with_stdout_checked(exit_status);
}
