// Atomic file replacement, write-through for devices, locked temporaries; see atomic_file.hpp.
#include "report/atomic_file.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <streambuf>
#include <string_view>
#include <utility>
#include <vector>

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace sidc {
namespace fs = std::filesystem;
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

bool fail_errno(std::string* why, const std::string& destination, int error) {
  return fail(why, destination, std::strerror(error ? error : EIO));
}

// A symbolic link's target is what gets replaced; the link itself stays.
std::string replaced_path(const std::string& destination) {
  struct stat st {};
  if (::lstat(destination.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return destination;
  std::error_code ec;
  const fs::path target = fs::weakly_canonical(destination, ec);
  return ec ? destination : target.string();
}

std::string folder_of(const std::string& path) {
  const fs::path p(path);
  return p.has_parent_path() ? p.parent_path().string() : ".";
}

// flock on a folder, held for this object's life; without a folder to open there is no lock (the
// write that follows then fails with the reason).
class FolderLock {
 public:
  explicit FolderLock(const std::string& folder) : descriptor_(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)) {
    if (descriptor_ >= 0)
      while (::flock(descriptor_, LOCK_EX) != 0 && errno == EINTR) {
      }
  }
  ~FolderLock() {
    if (descriptor_ >= 0) ::close(descriptor_);  // closing drops the lock
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  FolderLock(FolderLock&& other) noexcept : descriptor_(std::exchange(other.descriptor_, -1)) {}
  int descriptor() const { return descriptor_; }

 private:
  int descriptor_;
};

// Removes `.NAME.XXXXXX` files in `folder` that no live run holds locked: leftovers of killed runs.
// Called with the folder locked, so no run is between creating a temporary and locking it.
void remove_leftovers(const FolderLock& folder, const std::string& name) {
  if (folder.descriptor() < 0) return;
  const int listing = ::dup(folder.descriptor());
  if (listing < 0) return;
  DIR* entries = ::fdopendir(listing);
  if (!entries) {
    ::close(listing);
    return;
  }
  const std::string prefix = "." + name + ".";
  std::vector<std::string> leftovers;
  while (const dirent* entry = ::readdir(entries)) {
    const std::string_view candidate(entry->d_name);
    if (candidate.size() != prefix.size() + 6 || !candidate.starts_with(prefix)) continue;
    if (!std::all_of(candidate.end() - 6, candidate.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0; })) continue;
    leftovers.emplace_back(candidate);
  }
  ::closedir(entries);
  for (const auto& leftover : leftovers) {
    const int fd = ::openat(folder.descriptor(), leftover.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) continue;
    struct stat st {};
    if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && ::flock(fd, LOCK_EX | LOCK_NB) == 0) ::unlinkat(folder.descriptor(), leftover.c_str(), 0);
    ::close(fd);
  }
}

// An ostream's buffer over a file descriptor, keeping the first write error's errno.
class DescriptorBuffer : public std::streambuf {
 public:
  explicit DescriptorBuffer(int descriptor) : descriptor_(descriptor), buffer_(std::size_t{1} << 16) {
    setp(buffer_.data(), buffer_.data() + buffer_.size());
  }
  int error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    if (n < static_cast<std::streamsize>(buffer_.size())) return std::streambuf::xsputn(s, n);
    return drain() && write_all(s, static_cast<std::size_t>(n)) ? n : 0;  // large pieces skip the copy
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  bool drain() {
    const bool ok = write_all(pbase(), static_cast<std::size_t>(pptr() - pbase()));
    setp(buffer_.data(), buffer_.data() + buffer_.size());
    return ok;
  }
  bool write_all(const char* p, std::size_t n) {
    while (n > 0) {
      const ssize_t written = ::write(descriptor_, p, n);
      if (written < 0) {
        if (errno == EINTR) continue;
        if (error_ == 0) error_ = errno;
        return false;
      }
      p += written;
      n -= static_cast<std::size_t>(written);
    }
    return true;
  }

  int descriptor_;
  std::vector<char> buffer_;
  int error_ = 0;
};

// Runs `write` into `descriptor`; false with the errno (EIO when the writer gave up or threw).
bool write_into(int descriptor, const std::function<bool(std::ostream&)>& write, int* error) {
  DescriptorBuffer buffer(descriptor);
  std::ostream out(&buffer);
  bool ok = false;
  try {
    ok = write(out) && out.flush();
  } catch (...) {  // the writer threw: the caller removes what was half written
    ok = false;
  }
  *error = ok ? 0 : buffer.error() ? buffer.error() : EIO;
  return ok;
}

// The descriptor a path names itself (/dev/stdout, /dev/stderr, /dev/fd/N, /proc/self/fd/N), or -1.
int named_descriptor(const std::string& path) {
  if (path == "/dev/stdout") return 1;
  if (path == "/dev/stderr") return 2;
  for (const std::string_view prefix : {"/dev/fd/", "/proc/self/fd/"}) {
    if (!path.starts_with(prefix) || path.size() == prefix.size()) continue;
    const std::string_view digits = std::string_view(path).substr(prefix.size());
    if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }) || digits.size() > 9) return -1;
    return std::stoi(std::string(digits));
  }
  return -1;
}

// Writes straight into a device, a FIFO or an open descriptor. A descriptor the path names itself
// (/dev/stdout) is written through a duplicate, after what the program printed there so far: a
// second open of the same file (`sidc ... -o /dev/stdout > out.txt`) would have an offset of its
// own, and the two would overwrite each other. Anything else is opened for appending (nothing is
// truncated).
bool write_through(const std::string& destination, const std::function<bool(std::ostream&)>& write, std::string* why) {
  const int named = named_descriptor(destination);
  if (named >= 0) {
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
  }
  const int fd = named >= 0 ? ::fcntl(named, F_DUPFD_CLOEXEC, 0) : ::open(destination.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd < 0) return fail_errno(why, destination, errno);
  int error = 0;
  const bool ok = write_into(fd, write, &error);
  if (::close(fd) != 0 && ok) return fail_errno(why, destination, errno);
  return ok || fail_errno(why, destination, error);
}

bool is_folder(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool sync_file(int descriptor) {
  while (::fsync(descriptor) != 0) {
    if (errno == EINTR) continue;
    return errno == EINVAL || errno == EROFS;  // a file system that cannot sync has nothing to lose
  }
  return true;
}

}  // namespace

bool is_written_through(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return false;  // does not exist (yet): created as a file
  if (!S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode)) return true;
  std::error_code ec;
  const std::string named = fs::absolute(path, ec).lexically_normal().string();
  return !ec && (named == "/dev/stdout" || named == "/dev/stderr" || named.starts_with("/dev/fd/") || named.starts_with("/proc/"));
}

std::string input_overwritten_by(const std::string& output, const std::vector<std::string>& inputs) {
  struct stat out {};
  if (output.empty() || ::stat(output.c_str(), &out) != 0 || !S_ISREG(out.st_mode)) return "";  // nothing there to lose
  for (const auto& input : inputs) {
    struct stat in {};
    if (!input.empty() && ::stat(input.c_str(), &in) == 0 && in.st_dev == out.st_dev && in.st_ino == out.st_ino) return input;
  }
  return "";
}

TemporaryFile::TemporaryFile(TemporaryFile&& other) noexcept
    : path_(std::exchange(other.path_, {})), descriptor_(std::exchange(other.descriptor_, -1)) {}

TemporaryFile& TemporaryFile::operator=(TemporaryFile&& other) noexcept {
  if (this != &other) {
    remove();
    path_ = std::exchange(other.path_, {});
    descriptor_ = std::exchange(other.descriptor_, -1);
  }
  return *this;
}

TemporaryFile::~TemporaryFile() { remove(); }

void TemporaryFile::release() {
  if (descriptor_ >= 0) ::close(descriptor_);
  descriptor_ = -1;
  path_.clear();
}

void TemporaryFile::remove() {
  if (!path_.empty()) ::unlink(path_.c_str());  // unlinked before the lock drops: never seen unlocked
  release();
}

TemporaryFile create_temporary_beside(const std::string& destination, std::string* why) {
  if (destination.empty()) {
    fail(why, destination, "no file name");
    return {};
  }
  const std::string target = replaced_path(destination);
  if (is_folder(target)) {
    fail_errno(why, destination, EISDIR);
    return {};
  }
  const fs::path path(target);
  const std::string folder = folder_of(target);
  std::string pattern = (fs::path(folder) / ("." + path.filename().string() + ".XXXXXX")).string();
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  const FolderLock lock(folder);
  remove_leftovers(lock, path.filename().string());
  const int fd = ::mkostemp(buffer.data(), O_CLOEXEC);
  if (fd < 0) {
    fail_errno(why, destination, errno);
    return {};
  }
  ::flock(fd, LOCK_EX | LOCK_NB);  // just made, so free: cannot fail but for lack of memory
  // mkstemp makes the file private (0600); give it the mode a newly created file gets here
  // (0666 less the umask), as any other program's output would have.
  ::fchmod(fd, 0666 & ~process_umask());
  return TemporaryFile(std::string(buffer.data()), fd);
}

bool write_temporary(TemporaryFile& temporary, const std::string& content, std::string* why) {
  int error = 0;
  return write_into(temporary.descriptor(), [&](std::ostream& out) { return static_cast<bool>(out.write(content.data(), static_cast<std::streamsize>(content.size()))); }, &error) ||
         fail_errno(why, temporary.path(), error);
}

bool replace_file(TemporaryFile& temporary, const std::string& destination, std::string* why) {
  if (is_written_through(destination)) {
    const int fd = temporary.descriptor();
    const bool copied = write_through(destination, [fd](std::ostream& out) {
      std::vector<char> chunk(std::size_t{1} << 16);
      for (off_t at = 0;;) {
        const ssize_t got = ::pread(fd, chunk.data(), chunk.size(), at);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) return false;
        if (got == 0) return true;
        if (!out.write(chunk.data(), got)) return false;
        at += got;
      }
    }, why);
    temporary.remove();
    return copied;
  }
  if (!sync_file(temporary.descriptor())) {
    const int error = errno;
    temporary.remove();
    return fail_errno(why, destination, error);
  }
  const std::string target = replaced_path(destination);
  const FolderLock lock(folder_of(target));
  if (std::rename(temporary.path().c_str(), target.c_str()) != 0) {
    const int error = errno;
    temporary.remove();
    return fail_errno(why, destination, error);
  }
  temporary.release();
  if (lock.descriptor() >= 0) sync_file(lock.descriptor());
  return true;
}

bool AtomicFileSet::add(const std::string& destination, const std::function<bool(std::ostream&)>& write, std::string* why) {
  if (is_written_through(destination)) return write_through(destination, write, why);
  TemporaryFile temporary = create_temporary_beside(destination, why);
  if (temporary.empty()) return false;
  int error = 0;
  if (!write_into(temporary.descriptor(), write, &error)) return fail_errno(why, destination, error);  // the temporary goes with it
  if (!sync_file(temporary.descriptor())) return fail_errno(why, destination, errno);
  staged_.push_back({destination, replaced_path(destination), std::move(temporary)});
  return true;
}

bool AtomicFileSet::add(const std::string& destination, const std::string& content, std::string* why) {
  return add(destination, [&](std::ostream& out) { return static_cast<bool>(out.write(content.data(), static_cast<std::streamsize>(content.size()))); }, why);
}

bool AtomicFileSet::commit(std::string* why, const std::vector<std::string>& stale) {
  std::vector<std::string> folders;
  for (const auto& s : staged_) folders.push_back(folder_of(s.target));
  std::sort(folders.begin(), folders.end());  // one order for every run: no deadlock between two sets
  folders.erase(std::unique(folders.begin(), folders.end()), folders.end());
  std::vector<FolderLock> locks;
  for (const auto& folder : folders) locks.emplace_back(folder);
  bool ok = true;
  for (auto& s : staged_) {
    if (!ok) break;  // the rest are removed with the set
    if (std::rename(s.temporary.path().c_str(), s.target.c_str()) != 0) {
      ok = fail_errno(why, s.destination, errno);
      continue;
    }
    s.temporary.release();
  }
  if (ok)
    for (const auto& path : stale) {
      struct stat st {};
      if (::lstat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) ::unlink(path.c_str());
    }
  for (const auto& lock : locks)
    if (lock.descriptor() >= 0) sync_file(lock.descriptor());
  staged_.clear();
  return ok;
}

bool write_file_atomically(const std::string& destination, const std::function<bool(std::ostream&)>& write, std::string* why) {
  AtomicFileSet set;
  return set.add(destination, write, why) && set.commit(why);
}

bool write_file_atomically(const std::string& destination, const std::string& content, std::string* why) {
  AtomicFileSet set;
  return set.add(destination, content, why) && set.commit(why);
}

}  // namespace sidc
