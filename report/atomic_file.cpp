// Atomic file replacement; see atomic_file.hpp.
#include "report/atomic_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

namespace sidc {

std::string create_temporary_beside(const std::string& destination, std::string* why) {
  const std::filesystem::path path(destination);
  const std::filesystem::path directory = path.has_parent_path() ? path.parent_path() : ".";
  std::string pattern = (directory / ("." + path.filename().string() + ".XXXXXX")).string();
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  const int fd = ::mkstemp(buffer.data());
  if (fd < 0) {
    if (why) *why = "cannot create a temporary file beside " + destination + ": " + std::strerror(errno);
    return "";
  }
  // mkstemp makes the file private (0600); a picture or a report is meant to be read by others.
  ::fchmod(fd, 0644);
  ::close(fd);
  return std::string(buffer.data());
}

bool replace_file(const std::string& temporary, const std::string& destination, std::string* why) {
  if (std::rename(temporary.c_str(), destination.c_str()) != 0) {
    if (why) *why = "cannot rename " + temporary + " to " + destination + ": " + std::strerror(errno);
    std::remove(temporary.c_str());
    return false;
  }
  return true;
}

bool write_file_atomically(const std::string& destination, const std::string& content, std::string* why) {
  const std::string temporary = create_temporary_beside(destination, why);
  if (temporary.empty()) return false;
  std::FILE* file = std::fopen(temporary.c_str(), "wb");
  bool ok = file != nullptr;
  if (ok) ok = std::fwrite(content.data(), 1, content.size(), file) == content.size();
  if (file) ok = (std::fflush(file) == 0) && ok, ok = (std::fclose(file) == 0) && ok;
  if (!ok) {
    if (why) *why = "cannot write " + temporary + ": " + std::strerror(errno);
    std::remove(temporary.c_str());
    return false;
  }
  return replace_file(temporary, destination, why);
}

}  // namespace sidc
