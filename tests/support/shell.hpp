// Test support for the tests that run the `sidc` binary (tests/thesis, tests/nist,
// tests/silverbox): quoting for the shell, and reading a file whole.
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

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

}  // namespace sidc::testing
