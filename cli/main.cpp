// sidc: determination of parameters and operations in dynamic systems (Bernhart, 1964).
// This file only dispatches to the subcommands; each lives in its own *_command.cpp.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "cli/compile_command.hpp"
#include "cli/exit_codes.hpp"
#include "cli/fit_command.hpp"
#include "cli/simulate_command.hpp"
#include "cli/select_command.hpp"

int main(int argc, char** argv) {
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
      return code == 0 ? sidc::exit_code::success : sidc::exit_code::usage_error;
    }
  } catch (const std::exception& e) {
    std::cerr << "internal error: " << e.what() << "\nThis is a bug in sidc; please report it with the input that caused it.\n";
    return sidc::exit_code::internal_error;
  }
  return exit_status;
}
