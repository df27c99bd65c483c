// Reading a file sidc is told to read (a model, a compiled model, a parameter file, a record):
// only a regular file, whole, into a buffer sized from the file's own size, or (a large record)
// piece by piece through OpenFile.
//
// A FIFO, a device (/dev/zero, a terminal) or a socket is refused at once, with no byte read: the
// file is opened without blocking (O_NONBLOCK, so a FIFO with no writer does not hang the open)
// and checked with fstat before anything is read. The bytes are read with read(2), not mapped, so
// a file that another process truncates while it is read cannot end sidc with SIGBUS: a file whose
// length differs from the size fstat gave (shrunk or grown meanwhile) is refused as changed.
//
// Relies on: POSIX open, fstat, read. Guarantees: no exception; at most the file's size plus one
// byte is allocated; every refusal says why in words ("it is a FIFO").
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <variant>

namespace sidc {

// Frees a FileBytes buffer: anonymous memory for a large file (mapped with transparent huge pages,
// so that the kernel's copy faults 2 MB at a time, not 4 KB), new[] for a small one.
struct ReleaseFileBuffer {
  std::size_t mapped = 0;  // bytes mapped; 0: allocated with new[]
  void operator()(char* p) const;
};

// A file's bytes, in an uninitialised buffer (zeroing a 400 MB record first would cost a tenth of
// its parse).
struct FileBytes {
  std::unique_ptr<char[], ReleaseFileBuffer> data;
  std::size_t size = 0;
};

struct FileRefusal {
  enum class Kind { cannot_open, directory, not_regular, changed, no_memory } kind;
  std::string reason;  // "No such file or directory", "a FIFO", "it was 812 bytes long when opened, then 400"
};

std::variant<FileBytes, FileRefusal> read_regular_file(const std::string& path);

// A regular file opened for reading piece by piece (a record read in bounded chunks): the same
// refusals as read_regular_file, before any byte is read. The caller reads with read_at and
// compares what it read in all with `size` (a file that changed meanwhile is refused by
// changed_while_read's words).
class OpenFile {
 public:
  OpenFile(int descriptor, std::size_t size) : descriptor_(descriptor), size_(size) {}
  ~OpenFile();
  OpenFile(OpenFile&& other) noexcept : descriptor_(other.descriptor_), size_(other.size_) { other.descriptor_ = -1; }
  OpenFile(const OpenFile&) = delete;
  OpenFile& operator=(const OpenFile&) = delete;
  OpenFile& operator=(OpenFile&&) = delete;
  std::size_t size() const { return size_; }  // fstat's, when opened
  int descriptor() const { return descriptor_; }
  // Bytes [offset, offset + n) into `into`: the count read (fewer only at the file's end), or -errno.
  long long read_at(char* into, std::size_t offset, std::size_t n) const;

 private:
  friend std::variant<OpenFile, FileRefusal> open_regular_file(const std::string& path);
  int descriptor_;
  std::size_t size_;
};

std::variant<OpenFile, FileRefusal> open_regular_file(const std::string& path);

// The refusal of a file that was `expected` bytes long when opened and `read` when read.
FileRefusal changed_while_read(std::size_t expected, std::size_t read);

// The reading part of read_regular_file, on an open descriptor whose fstat gave `expected_size`
// bytes (tests give a size the file does not have, as a file shrunk or grown after its fstat).
std::variant<FileBytes, FileRefusal> read_open_file(int descriptor, std::size_t expected_size);

}  // namespace sidc
