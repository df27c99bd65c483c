// Whole regular files, read, never mapped; see regular_file.hpp.
#include "diagnostics/regular_file.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fmt/format.h>
#include <new>
#include <thread>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

namespace sidc {
namespace {

std::string kind_of_file(mode_t mode) {
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "a special file";
}

class Descriptor {
 public:
  explicit Descriptor(int fd) : fd_(fd) {}
  ~Descriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

// Buffers from this size up are anonymous mappings with huge pages: a 480 MB record's read then
// takes a few hundred page faults instead of 117,000.
constexpr std::size_t kMappedBufferFrom = std::size_t{8} << 20;
constexpr std::size_t kHugePage = std::size_t{2} << 20;

std::unique_ptr<char[], ReleaseFileBuffer> allocate(std::size_t size) {
  if (size < kMappedBufferFrom) return std::unique_ptr<char[], ReleaseFileBuffer>(new (std::nothrow) char[size]);
  const std::size_t length = (size + kHugePage - 1) / kHugePage * kHugePage;
  void* p = ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) return std::unique_ptr<char[], ReleaseFileBuffer>(nullptr, ReleaseFileBuffer{length});
  ::madvise(p, length, MADV_HUGEPAGE);
  return std::unique_ptr<char[], ReleaseFileBuffer>(static_cast<char*>(p), ReleaseFileBuffer{length});
}

}  // namespace

void ReleaseFileBuffer::operator()(char* p) const {
  if (!p) return;
  if (mapped) ::munmap(p, mapped);
  else delete[] p;
}

namespace {

// Reads [from, to) of the file into data + from, in pieces (pread moves at most about 2 GB at a
// time, and a short read is not the end); the bytes read, fewer at the real end; -errno on failure.
long long read_range(int descriptor, char* data, std::size_t from, std::size_t to) {
  std::size_t at = from;
  while (at < to) {
    const std::size_t piece = std::min<std::size_t>(to - at, std::size_t{1} << 30);
    const ssize_t got = ::pread(descriptor, data + at, piece, static_cast<off_t>(at));
    if (got < 0) {
      if (errno == EINTR) continue;
      return -errno;
    }
    if (got == 0) break;  // the real end, wherever it is now
    at += static_cast<std::size_t>(got);
  }
  return static_cast<long long>(at - from);
}

// From this size on, the two halves are read on two threads: the cost is the fresh buffer's pages
// (zeroed and mapped by the kernel), which two cores share.
constexpr std::size_t kTwoThreadsFrom = std::size_t{64} << 20;

}  // namespace

std::variant<FileBytes, FileRefusal> read_open_file(int descriptor, std::size_t expected_size) {
  // One byte more than expected, to see a file that grew since its fstat.
  auto data = allocate(expected_size + 1);
  if (!data) return FileRefusal{FileRefusal::Kind::no_memory, fmt::format("not enough memory to hold its {} bytes", expected_size)};
  const std::size_t half = expected_size >= kTwoThreadsFrom && std::thread::hardware_concurrency() >= 2 ? expected_size / 2 : expected_size;
  long long second = 0;
  std::thread other;
  if (half < expected_size) other = std::thread([&] { second = read_range(descriptor, data.get(), half, expected_size + 1); });
  const long long first = read_range(descriptor, data.get(), 0, half);
  if (other.joinable()) other.join();
  for (const long long got : {first, second})
    if (got < 0) return FileRefusal{FileRefusal::Kind::cannot_open, std::strerror(static_cast<int>(-got))};
  // A short first half is a file that shrank; then the second half's count means nothing.
  long long used = first;
  if (first == static_cast<long long>(half) && half < expected_size) used += second;
  else if (first == static_cast<long long>(half)) {
    const long long beyond = read_range(descriptor, data.get(), half, half + 1);  // grown past its size?
    if (beyond < 0) return FileRefusal{FileRefusal::Kind::cannot_open, std::strerror(static_cast<int>(-beyond))};
    used += beyond;
  }
  const auto read_bytes = static_cast<std::size_t>(used);
  if (read_bytes != expected_size)
    return FileRefusal{FileRefusal::Kind::changed, fmt::format("it changed while it was read ({} bytes long when opened, {} when read{})", expected_size,
                                                               read_bytes, read_bytes > expected_size ? " at least" : "")};
  return FileBytes{std::move(data), read_bytes};
}

std::variant<FileBytes, FileRefusal> read_regular_file(const std::string& path) {
  const Descriptor file(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
  if (file.get() < 0) return FileRefusal{FileRefusal::Kind::cannot_open, std::strerror(errno)};
  struct stat st {};
  if (::fstat(file.get(), &st) != 0) return FileRefusal{FileRefusal::Kind::cannot_open, std::strerror(errno)};
  if (S_ISDIR(st.st_mode)) return FileRefusal{FileRefusal::Kind::directory, "a directory"};
  if (!S_ISREG(st.st_mode)) return FileRefusal{FileRefusal::Kind::not_regular, kind_of_file(st.st_mode)};
  ::fcntl(file.get(), F_SETFL, 0);  // back to blocking reads (a regular file never blocks anyway)
  ::posix_fadvise(file.get(), 0, 0, POSIX_FADV_SEQUENTIAL);
  return read_open_file(file.get(), static_cast<std::size_t>(st.st_size));
}

}  // namespace sidc
