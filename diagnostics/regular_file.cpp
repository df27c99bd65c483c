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

// Reads file bytes [offset, offset + n) into `into`, in pieces (pread moves at most about 2 GB at
// a time, and a short read is not the end); the bytes read, fewer at the real end; -errno on failure.
long long read_range(int descriptor, char* into, std::size_t offset, std::size_t n) {
  std::size_t done = 0;
  while (done < n) {
    const std::size_t piece = std::min<std::size_t>(n - done, std::size_t{1} << 30);
    const ssize_t got = ::pread(descriptor, into + done, piece, static_cast<off_t>(offset + done));
    if (got < 0) {
      if (errno == EINTR) continue;
      return -errno;
    }
    if (got == 0) break;  // the real end, wherever it is now
    done += static_cast<std::size_t>(got);
  }
  return static_cast<long long>(done);
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
  if (half < expected_size) other = std::thread([&] { second = read_range(descriptor, data.get() + half, half, expected_size + 1 - half); });
  const long long first = read_range(descriptor, data.get(), 0, half);
  if (other.joinable()) other.join();
  for (const long long got : {first, second})
    if (got < 0) return FileRefusal{FileRefusal::Kind::cannot_open, std::strerror(static_cast<int>(-got))};
  // A short first half is a file that shrank; then the second half's count means nothing.
  long long used = first;
  if (first == static_cast<long long>(half) && half < expected_size) used += second;
  else if (first == static_cast<long long>(half)) {
    const long long beyond = read_range(descriptor, data.get() + half, half, 1);  // grown past its size?
    if (beyond < 0) return FileRefusal{FileRefusal::Kind::cannot_open, std::strerror(static_cast<int>(-beyond))};
    used += beyond;
  }
  const auto read_bytes = static_cast<std::size_t>(used);
  if (read_bytes != expected_size) return changed_while_read(expected_size, read_bytes);
  return FileBytes{std::move(data), read_bytes};
}

FileRefusal changed_while_read(std::size_t expected, std::size_t read) {
  return FileRefusal{FileRefusal::Kind::changed, fmt::format("it changed while it was read ({} bytes long when opened, {} when read{})", expected,
                                                             read, read > expected ? " at least" : "")};
}

std::variant<OpenFile, FileRefusal> open_regular_file(const std::string& path) {
  OpenFile file(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC), 0);  // closed on every refusal below
  if (file.descriptor_ < 0) return FileRefusal{FileRefusal::Kind::cannot_open, std::strerror(errno)};
  struct stat st {};
  if (::fstat(file.descriptor_, &st) != 0) return FileRefusal{FileRefusal::Kind::cannot_open, std::strerror(errno)};
  if (S_ISDIR(st.st_mode)) return FileRefusal{FileRefusal::Kind::directory, "a directory"};
  if (!S_ISREG(st.st_mode)) return FileRefusal{FileRefusal::Kind::not_regular, kind_of_file(st.st_mode)};
  ::fcntl(file.descriptor_, F_SETFL, 0);  // back to blocking reads (a regular file never blocks anyway)
  ::posix_fadvise(file.descriptor_, 0, 0, POSIX_FADV_SEQUENTIAL);
  file.size_ = static_cast<std::size_t>(st.st_size);
  return file;
}

OpenFile::~OpenFile() {
  if (descriptor_ >= 0) ::close(descriptor_);
}

long long OpenFile::read_at(char* into, std::size_t offset, std::size_t n) const { return read_range(descriptor_, into, offset, n); }

std::variant<FileBytes, FileRefusal> read_regular_file(const std::string& path) {
  auto opened = open_regular_file(path);
  if (auto* refusal = std::get_if<FileRefusal>(&opened)) return std::move(*refusal);
  const OpenFile& file = std::get<OpenFile>(opened);
  return read_open_file(file.descriptor(), file.size());
}

}  // namespace sidc
