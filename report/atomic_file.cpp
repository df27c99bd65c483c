// Atomic file replacement; see atomic_file.hpp.
#include "report/atomic_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

namespace sidc {
namespace {

// The umask cannot be read without setting it; read it once, before any thread writes files.
mode_t process_umask() {
  static const mode_t mask = [] {
    const mode_t m = ::umask(0);
    ::umask(m);
    return m;
  }();
  return mask;
}

bool fail(std::string* why, const std::string& destination, const std::string& reason) {
  if (why) *why = "cannot write `" + destination + "`: " + reason;
  return false;
}

}  // namespace

std::string create_temporary_beside(const std::string& destination, std::string* why) {
  const std::filesystem::path path(destination);
  const std::filesystem::path directory = path.has_parent_path() ? path.parent_path() : ".";
  std::string pattern = (directory / ("." + path.filename().string() + ".XXXXXX")).string();
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  const int fd = ::mkstemp(buffer.data());
  if (fd < 0) {
    fail(why, destination, std::strerror(errno));
    return "";
  }
  // mkstemp makes the file private (0600); give it the mode a newly created file gets here
  // (0666 less the umask), as any other program's output would have.
  ::fchmod(fd, 0666 & ~process_umask());
  ::close(fd);
  return std::string(buffer.data());
}

bool replace_file(const std::string& temporary, const std::string& destination, std::string* why) {
  if (std::rename(temporary.c_str(), destination.c_str()) != 0) {
    const int error = errno;
    std::remove(temporary.c_str());
    return fail(why, destination, std::strerror(error));
  }
  return true;
}

bool write_file_atomically(const std::string& destination, const std::function<bool(std::ostream&)>& write, std::string* why) {
  const std::string temporary = create_temporary_beside(destination, why);
  if (temporary.empty()) return false;
  bool ok = false;
  int error = 0;
  try {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    ok = out && write(out) && out.flush();
    out.close();  // a failure reported only at close (a full disk, NFS) must not be renamed into place
    ok = ok && !out.fail();
    error = errno;
  } catch (...) {  // the writer threw: nothing half-written may stay behind
    ok = false;
    error = EIO;
  }
  if (!ok) {
    std::remove(temporary.c_str());
    return fail(why, destination, std::strerror(error ? error : EIO));
  }
  return replace_file(temporary, destination, why);
}

bool write_file_atomically(const std::string& destination, const std::string& content, std::string* why) {
  return write_file_atomically(destination, [&](std::ostream& out) { return static_cast<bool>(out.write(content.data(), static_cast<std::streamsize>(content.size()))); }, why);
}

}  // namespace sidc
