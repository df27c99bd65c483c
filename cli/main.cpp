// sidc: determination of parameters and operations in dynamic systems (Bernhart, 1964).
// This file only dispatches to the subcommands; each lives in its own *_command.cpp.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "cli/compile_command.hpp"
#include "cli/exit_codes.hpp"
#include "cli/export_command.hpp"
#include "cli/fit_command.hpp"
#include "cli/simulate_command.hpp"
#include "cli/select_command.hpp"
#include "distributed/session.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "diagnostics/model_catalogue.hpp"

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

int run_command(int argc, char** argv, const sidc::distributed::Session& session) {
  std::signal(SIGPIPE, SIG_IGN);
  // Only `fit` and `select` share their work among ranks; any other command runs on rank 0 alone, so
  // that two ranks never write the same file.
  if (session.size() > 1 && !session.is_writer() && (argc < 2 || (std::string(argv[1]) != "fit" && std::string(argv[1]) != "select")))
    return sidc::exit_code::success;
  CLI::App app{"sidc: identify the parameters and operations of dynamic systems from recorded data\n"
               "(the method of W. D. Bernhart, 1964). Main path: sidc compile model.sid && sidc fit"};
  app.name("sidc");  // in --help, whatever path the binary was run by
  app.set_version_flag("--version", std::string("sidc ") + SIDC_VERSION);
  app.require_subcommand(1);
  int exit_status = sidc::exit_code::success;
  try {
    sidc::add_compile_command(app, exit_status);
    sidc::add_fit_command(app, exit_status);
    sidc::add_simulate_command(app, exit_status);
    sidc::add_select_command(app, exit_status);
    sidc::add_export_command(app, exit_status);
    // `sidc fitt`: CLI11 would say only that a subcommand is required; name the word and the nearest.
    std::vector<std::string> names;
    for (const auto* sub : app.get_subcommands(std::function<bool(CLI::App*)>{})) names.push_back(sub->get_name());
    if (argc > 1 && argv[1][0] != '-' && std::find(names.begin(), names.end(), argv[1]) == names.end()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      return sidc::fail(render(sidc::cli_diag::unknown_subcommand(argv[1], sidc::diag::nearest(argv[1], names), list)),
                        sidc::exit_code::usage_error);
    }
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      if (e.get_exit_code() == 0) return with_stdout_checked(app.exit(e));  // --help, --version: printed, success
      // A usage error, in sidc's own error:/hint: frame, pointing at the subcommand's --help.
      std::string command = "sidc";
      for (const auto* sub : app.get_subcommands()) command += " " + sub->get_name();
      return sidc::fail(render(sidc::cli_diag::usage(e.what(), command)), sidc::exit_code::usage_error);
    }
  } catch (const std::exception& e) {
    std::cerr << "internal error: " << e.what() << "\nThis is a bug in sidc; please report it with the input that caused it.\n";
    return sidc::exit_code::internal_error;
  }
  return with_stdout_checked(exit_status);
}

}  // namespace

int main(int argc, char** argv) {
  // Under mpirun, every rank; one process otherwise (distributed/session.hpp). Every return below
  // goes through finish(), the ranks' last exchange.
  auto& session = sidc::distributed::Session::start(argc, argv);
  if (!session.launch_problem().empty()) {
    if (session.is_writer())
      std::cerr << sidc::render(sidc::diag::error("no-mpi", {}, session.launch_problem(),
                                                  "rebuild with Open MPI (bash scripts/setup.sh installs libopenmpi-dev and openmpi-bin), "
                                                  "or run sidc without mpirun"))
                << "\n";
    return sidc::exit_code::usage_error;
  }
  return session.finish(run_command(argc, argv, session));
}
