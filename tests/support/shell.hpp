// Test support for the tests that run the `sidc` binary (tests/thesis, tests/nist,
// tests/silverbox, tests/report, tests/select): quoting for the shell, reading a file whole, and
// running a command with its output captured.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>

namespace sidc::testing {

// Single-quoted for /bin/sh, embedded quotes escaped. Built with += because GCC 12 gives a false
// -Wrestrict warning on "'" + std::string + "'".
// Takes a path, which a std::string or a literal converts to as it is (POSIX paths are bytes).
inline std::string shell_quoted(const std::filesystem::path& path) {
  std::string out(1, '\'');
  for (char c : path.string()) {
    if (c == '\'') out += "'\\''";
    else out += c;
  }
  out += '\'';
  return out;
}

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A command's exit status (-1 when it did not exit normally) and what it wrote on each stream.
struct CommandRun {
  int status = -1;
  std::string out, err;
};

// Runs the shell command line `command` with stderr into `err` and stdout into `out` (or, when
// `stdout_to` is given, into that shell redirection target instead: `/dev/full`, a FIFO).
inline CommandRun run_captured(const std::string& command, const std::filesystem::path& out,
                               const std::filesystem::path& err, const std::string& stdout_to = "") {
  const std::string line = command + " >" + (stdout_to.empty() ? shell_quoted(out) : stdout_to) + " 2>" + shell_quoted(err);
  const int raw = std::system(line.c_str());
  CommandRun run;
  run.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  run.out = read_text(out);
  run.err = read_text(err);
  return run;
}

}  // namespace sidc::testing
