#include "cli/read_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <sstream>

namespace sidc {

std::optional<std::string> read_whole_file(const std::string& path, std::string& error) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    error = fmt::format("error: `{}` is a directory, not a file", path);
    return std::nullopt;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = fmt::format("error: cannot read `{}`: {}", path, std::strerror(errno));
    return std::nullopt;
  }
  std::ostringstream contents;
  contents << in.rdbuf();
  return std::move(contents).str();
}

bool write_file_atomically(const std::string& path, const std::function<bool(std::ostream&)>& write, std::string& error) {
  const std::string temporary = path + ".partial";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out || !write(out) || !(out.flush())) {
      error = fmt::format("error: cannot write `{}`: {}", path, std::strerror(errno));
      out.close();
      std::remove(temporary.c_str());
      return false;
    }
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    error = fmt::format("error: cannot write `{}`: {}", path, ec.message());
    std::remove(temporary.c_str());
    return false;
  }
  return true;
}

bool write_file_atomically(const std::string& path, const std::string& contents, std::string& error) {
  return write_file_atomically(path, [&](std::ostream& out) { return static_cast<bool>(out << contents); }, error);
}

}  // namespace sidc
