// CSV files as read_csv reads them (records.hpp): a file up to CsvOptions::chunk_bytes read whole
// into one buffer sized from the file, a larger one in pieces that end at line ends
// (read_csv_in_pieces: the text is never held whole, and the next piece is read while one is
// parsed), never mapped (a file truncated while mapped ends the process with SIGBUS;
// diagnostics/regular_file.hpp). Under mpirun each process reads one byte range of the file and
// the parts are put together (read_csv_by_parts). The parsing itself is csv_parser.hpp's.
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fmt/format.h>
#include <future>
#include <memory>
#include <new>
#include <optional>
#include <system_error>

#include "diagnostics/regular_file.hpp"
#include "runtime/records/csv_parser.hpp"
#include "runtime/records/part_share.hpp"
#include "runtime/records/records.hpp"

namespace sidc {

using csv::CsvParser;

namespace {

Diagnostic refused(const std::string& path, const FileRefusal& refusal) {
  switch (refusal.kind) {
    case FileRefusal::Kind::directory: return data_diag::is_directory(path);
    case FileRefusal::Kind::not_regular: return data_diag::not_a_regular_file(path, refusal.reason);
    case FileRefusal::Kind::changed: return data_diag::changed_while_read(path, refusal.reason);
    case FileRefusal::Kind::cannot_open: break;
    case FileRefusal::Kind::no_memory: return data_diag::cannot_open(path, refusal.reason);
  }
  return data_diag::cannot_open(path, refusal.reason == std::strerror(ENOENT) ? "no such file" : refusal.reason);
}

// Below: a file larger than CsvOptions::chunk_bytes, read and parsed piece by piece (each piece
// ends at a line end; a longer line grows the buffer), so memory is a piece, not the file; and a
// file read by cooperating processes, each its own byte range (read_csv_by_parts). Every answer is
// the whole file's, as parse_csv gives it: a file that changed while read is refused first, a NUL
// byte anywhere next (the rest is still read for both), then the first parse problem.

// The file's first lines, read from its start in pieces of 64 KiB and more until the first line
// that is neither blank nor a comment is whole (or the file ends), then given to begin_text.
struct HeaderRead {
  std::optional<Diagnostic> failure;  // the file could not be read
  std::optional<Diagnostic> binary;   // a NUL byte among the bytes read
  std::optional<Diagnostic> problem;  // begin_text's: an empty file, a bad header line
  std::size_t read = 0;               // bytes read from the start
  std::size_t newlines = 0;           // '\n' bytes among them
  std::size_t rows_begin = 0;         // without a problem: where the rows begin
  std::size_t newlines_before_rows = 0;
};

HeaderRead read_header(const OpenFile& file, const std::string& path, CsvParser& parser) {
  HeaderRead out;
  std::size_t want = std::min<std::size_t>(file.size(), std::size_t{1} << 16);
  std::unique_ptr<char[]> text;
  std::string_view prefix;
  for (;;) {
    text.reset(new (std::nothrow) char[std::max<std::size_t>(want, 1)]);
    if (!text) {
      out.failure = data_diag::cannot_open(path, fmt::format("not enough memory for a line of over {} bytes", want / 2));
      return out;
    }
    const long long got = want > 0 ? file.read_at(text.get(), 0, want) : 0;
    if (got < 0) {
      out.failure = data_diag::cannot_open(path, std::strerror(static_cast<int>(-got)));
      return out;
    }
    prefix = std::string_view(text.get(), static_cast<std::size_t>(got));
    if (static_cast<std::size_t>(got) < want || want >= file.size() || parser.holds_first_line(prefix) ||
        std::memchr(prefix.data(), '\0', prefix.size()))  // a binary file: no need to read on for a line end
      break;
    want = std::min(file.size(), 2 * want);
  }
  out.read = prefix.size();
  out.newlines = static_cast<std::size_t>(std::count(prefix.begin(), prefix.end(), '\n'));
  if (const auto nul = csv::first_nul(prefix.data(), prefix.data(), prefix.data() + prefix.size())) {
    out.binary = data_diag::binary_file(path, static_cast<int>(1 + nul->newlines), nul->column);
    return out;
  }
  parser.set_text(prefix);
  const char* p = nullptr;
  out.problem = parser.begin_text(p);
  if (!out.problem) {
    out.rows_begin = static_cast<std::size_t>(p - prefix.data());
    out.newlines_before_rows = static_cast<std::size_t>(std::count(prefix.data(), p, '\n'));
  }
  parser.set_text({});  // the prefix goes; the names begin_text read are the parser's own
  return out;
}

// Bytes [from, to) of `file` (on to the file's end when `to_end`), read in pieces of about
// CsvOptions::chunk_bytes that end at line ends and, when `parse`, given to parser.rows_of_text
// until it meets a problem; the bytes after that are still read, for a NUL byte.
struct RowsRead {
  std::optional<Diagnostic> failure;  // the file could not be read
  std::optional<Diagnostic> problem;  // the parser's first
  std::size_t read = 0;               // bytes read
  std::size_t newlines = 0;           // '\n' bytes among them, up to the first NUL
  std::optional<csv::NulByte> nul;    // the first NUL byte among them (its line ends counted from `from`)
};

// One read into `buffer` after the `held` bytes it keeps, and what read_rows notes of the new
// bytes: the line ends among them, and a NUL byte (the line ends before it, its column).
struct Refill {
  long long got = 0;  // bytes read, or -errno
  std::size_t newlines = 0;
  std::optional<csv::NulByte> nul;  // its line ends counted from the new bytes' start
};

Refill refill(const OpenFile& file, char* buffer, std::size_t held, std::size_t want, std::size_t offset, bool look_for_nul) {
  Refill r;
  r.got = want > 0 ? file.read_at(buffer + held, offset, want) : 0;
  if (r.got <= 0) return r;
  const char* first = buffer + held;
  const char* last = first + r.got;
  if (look_for_nul) r.nul = csv::first_nul(buffer, first, last);
  if (!r.nul) r.newlines = static_cast<std::size_t>(std::count(first, last, '\n'));
  return r;
}

RowsRead read_rows(const OpenFile& file, const std::string& path, CsvParser& parser, std::size_t from, std::size_t to, bool to_end,
                   bool parse, const CsvOptions& options) {
  RowsRead out;
  // Two buffers: the rows of one are parsed while the next piece is read into the other, on a
  // thread of its own when the pieces are large enough for that to pay. The read, the NUL search
  // and the line count had both parsing threads wait; read ahead, read_csv of fit_bench's 10^7-row
  // record went from 1.04-1.08 s to 0.88-0.94 s (two runs each, 2 cores).
  std::size_t capacity = std::max<std::size_t>(options.chunk_bytes > 0 ? options.chunk_bytes : std::size_t{16} << 20, 2);
  const bool read_ahead = capacity >= (std::size_t{1} << 20);
  std::unique_ptr<char[]> now(new (std::nothrow) char[capacity]), next;
  std::size_t next_capacity = 0;
  const auto no_memory = [&](std::string what) {
    out.failure = data_diag::cannot_open(path, fmt::format("not enough memory for {} of {} bytes", what, capacity));
    return out;
  };
  if (!now) return no_memory("a piece");
  const std::size_t last = to_end ? file.size() : to;  // for the progress line and the rows' estimate
  std::size_t held = 0;  // bytes read and still in `now`
  bool at_end = false, reserved = false;
  // Bytes to ask for at the current offset, `kept` bytes being in the buffer already.
  const auto wanted = [&](std::size_t kept) {
    const std::size_t offset = from + out.read;
    return to_end ? capacity - kept : std::min(capacity - kept, to > offset ? to - offset : 0);
  };
  const auto note = [&](const Refill& r) {
    if (r.got < 0) {
      out.failure = data_diag::cannot_open(path, std::strerror(static_cast<int>(-r.got)));
      return false;
    }
    if (!out.nul && r.nul) out.nul = csv::NulByte{out.newlines + r.nul->newlines, r.nul->column};
    if (!out.nul) out.newlines += r.newlines;
    at_end = r.got == 0;
    out.read += static_cast<std::size_t>(r.got);
    held += static_cast<std::size_t>(r.got);
    return true;
  };
  if (!note(refill(file, now.get(), 0, wanted(0), from, true))) return out;
  while (!at_end || held > 0) {
    if (to_end && from + out.read > file.size()) break;  // grown: the caller refuses it
    // The piece: up to the last line end (everything at the end).
    std::size_t cut = held;
    if (!at_end) {
      const char* end = now.get() + held;
      while (end > now.get() && *(end - 1) != '\n') --end;
      cut = static_cast<std::size_t>(end - now.get());
      if (cut == 0) {  // no whole line yet: read on into this buffer, doubled when full
        if (held == capacity) {
          std::unique_ptr<char[]> larger(new (std::nothrow) char[2 * capacity]);
          if (!larger) return no_memory("a line of over");
          std::memcpy(larger.get(), now.get(), held);
          now = std::move(larger);
          capacity *= 2;
        }
        if (!note(refill(file, now.get(), held, wanted(held), from + out.read, !out.nul))) return out;
        continue;
      }
    }
    // The bytes after the piece begin the next buffer, filled while the piece is parsed.
    std::future<Refill> filling;
    const std::size_t left = held - cut;
    if (!at_end) {
      if (next_capacity < capacity) {
        next.reset(new (std::nothrow) char[capacity]);
        if (!next) return no_memory("a piece");
        next_capacity = capacity;
      }
      std::memcpy(next.get(), now.get() + cut, left);
      auto task = [&file, buffer = next.get(), left, want = wanted(left), offset = from + out.read, look = !out.nul] {
        return refill(file, buffer, left, want, offset, look);
      };
      try {
        filling = std::async(read_ahead ? std::launch::async : std::launch::deferred, task);
      } catch (const std::system_error&) {  // no thread to be had: read after the parse
        filling = std::async(std::launch::deferred, task);
      }
    }
    if (parse && !out.nul && !out.problem) {
      const std::string_view piece(now.get(), cut);
      parser.set_text(piece);
      if (!reserved) parser.reserve_rows(piece.data(), last > from ? last - from : 0);
      reserved = true;
      out.problem = parser.rows_of_text(piece.data());
    }
    if (options.progress) options.progress(std::min(from + out.read, last), last);
    held = 0;
    if (filling.valid()) {
      std::swap(now, next);
      std::swap(capacity, next_capacity);
      held = left;
      if (!note(filling.get())) return out;
    }
  }
  return out;
}

std::variant<Record, Diagnostic> read_csv_in_pieces(const OpenFile& file, const std::string& path, const CsvOptions& options) {
  if (std::string why; !options.is_valid(&why)) return data_diag::invalid_csv_options(why);
  CsvParser parser(std::string_view(), path, options);
  const HeaderRead header = read_header(file, path, parser);
  if (header.failure) return *header.failure;
  // After a NUL byte or a problem in the first lines nothing more is parsed, but the rest is still
  // read: a file that changed comes first, and a NUL byte anywhere before a problem.
  const bool stopped = header.binary || header.problem;
  const std::size_t from = stopped ? header.read : header.rows_begin;
  const RowsRead rows = read_rows(file, path, parser, from, file.size(), true, !stopped, options);
  if (rows.failure) return *rows.failure;
  if (from + rows.read != file.size()) return data_diag::changed_while_read(path, changed_while_read(file.size(), from + rows.read).reason);
  if (header.binary) return *header.binary;
  const std::size_t newlines_before = header.problem ? header.newlines : header.newlines_before_rows;
  if (rows.nul) return data_diag::binary_file(path, static_cast<int>(1 + newlines_before + rows.nul->newlines), rows.nul->column);
  if (header.problem) return *header.problem;
  if (rows.problem) return *rows.problem;
  return parser.finish();
}

// The first line start at or after `offset` (the byte after a '\n'), the file's end when there is
// none; -errno when the file cannot be read.
long long line_start_at_or_after(const OpenFile& file, std::size_t offset) {
  if (offset == 0) return 0;
  std::vector<char> buffer(std::size_t{1} << 16);
  for (std::size_t at = offset - 1; at < file.size();) {
    const long long got = file.read_at(buffer.data(), at, buffer.size());
    if (got < 0) return got;
    if (got == 0) break;
    if (const void* newline = std::memchr(buffer.data(), '\n', static_cast<std::size_t>(got)))
      return static_cast<long long>(at) + (static_cast<const char*>(newline) - buffer.data()) + 1;
    at += static_cast<std::size_t>(got);
  }
  return static_cast<long long>(file.size());
}

// What one part has of the record's bookkeeping, as doubles for PartShare::merge: its rows and
// lines, each column's first faulty cells (row, fault, text), its line jumps.
std::vector<double> bookkeeping_state(std::size_t rows, int lines, const std::vector<std::vector<FaultyCell>>& faults,
                                      const std::vector<std::pair<std::size_t, int>>& jumps) {
  std::vector<double> out{static_cast<double>(rows), static_cast<double>(lines), static_cast<double>(faults.size())};
  for (const auto& kept : faults) {
    out.push_back(static_cast<double>(kept.size()));
    for (const auto& cell : kept) {
      out.insert(out.end(), {static_cast<double>(cell.row), static_cast<double>(cell.fault), static_cast<double>(cell.text.size())});
      for (char c : cell.text) out.push_back(static_cast<double>(static_cast<unsigned char>(c)));
    }
  }
  out.push_back(static_cast<double>(jumps.size()));
  for (const auto& [row, line] : jumps) out.insert(out.end(), {static_cast<double>(row), static_cast<double>(line)});
  return out;
}

struct Bookkeeping {
  std::size_t rows = 0;
  int lines = 0;
  std::vector<std::vector<FaultyCell>> faults;
  std::vector<std::pair<std::size_t, int>> jumps;
};

Bookkeeping bookkeeping_of(const std::vector<double>& state) {
  Bookkeeping b;
  std::size_t i = 0;
  const auto next = [&] { return state[i++]; };
  b.rows = static_cast<std::size_t>(next());
  b.lines = static_cast<int>(next());
  b.faults.resize(static_cast<std::size_t>(next()));
  for (auto& kept : b.faults) {
    kept.resize(static_cast<std::size_t>(next()));
    for (auto& cell : kept) {
      cell.row = static_cast<std::size_t>(next());
      cell.fault = static_cast<CellFault>(static_cast<int>(next()));
      cell.text.resize(static_cast<std::size_t>(next()));
      for (char& c : cell.text) c = static_cast<char>(static_cast<unsigned char>(next()));
    }
  }
  b.jumps.resize(static_cast<std::size_t>(next()));
  for (auto& [row, line] : b.jumps) {
    row = static_cast<std::size_t>(next());
    line = static_cast<int>(next());
  }
  return b;
}

// A file read by the parts of options.share (issue 17): each part reads and parses the byte range
// from the first line start at or after size * k / parts to the next part's start (every part reads
// the first lines for the header; no range begins before the rows do), its lines and rows numbered
// within the range; one exchange of every part's counts and outcome, and the answer is settled
// the same way on every part: a NUL byte (the first part's that has one, its row counted over the
// parts before), else a parse problem (the first part's, parsed again by every part with the
// file's line numbers), else every column put together in part order and the faulty cells and line
// jumps shifted by the rows and lines before them. The record is then parse_csv's, bit for bit.
std::variant<Record, Diagnostic> read_csv_by_parts(const OpenFile& file, const std::string& path, const CsvOptions& options) {
  if (std::string why; !options.is_valid(&why)) return data_diag::invalid_csv_options(why);
  PartShare& share = *options.share;
  const int part = share.part(), parts = share.parts();
  CsvParser parser(std::string_view(), path, options);
  const HeaderRead header = read_header(file, path, parser);
  if (header.failure) return *header.failure;  // this part leaves; the others learn it in the merge
  // The first lines are the same bytes for every part: a problem there is every part's, settled
  // as one process settles it.
  if (header.binary || header.problem) return read_csv_in_pieces(file, path, options);

  const std::size_t size = file.size();
  const auto start_of = [&](int k) -> long long {
    if (k == 0) return static_cast<long long>(header.rows_begin);
    if (k == parts) return static_cast<long long>(size);
    const std::size_t even = size / static_cast<std::size_t>(parts) * static_cast<std::size_t>(k) +
                             size % static_cast<std::size_t>(parts) * static_cast<std::size_t>(k) / static_cast<std::size_t>(parts);
    const long long start = line_start_at_or_after(file, even);
    return start < 0 ? start : std::max(start, static_cast<long long>(header.rows_begin));
  };
  const long long start = start_of(part), end = start_of(part + 1);
  if (start < 0 || end < 0) return data_diag::cannot_open(path, std::strerror(static_cast<int>(-std::min(start, end))));
  if (part > 0) parser.restart_lines(1);
  const auto from = static_cast<std::size_t>(start), to = static_cast<std::size_t>(std::max(start, end));
  RowsRead rows = read_rows(file, path, parser, from, to, part == parts - 1, true, options);
  if (rows.failure) return *rows.failure;

  // Every part's counts and outcome, in part order.
  enum Count { kProblem, kNul, kNulNewlines, kNulColumn, kRows, kLines, kNewlines, kFrom, kTo, kRead, kFields };
  std::vector<double> counts(kFields);
  counts[kProblem] = rows.problem ? 1 : 0;
  counts[kNul] = rows.nul ? 1 : 0;
  counts[kNulNewlines] = rows.nul ? static_cast<double>(rows.nul->newlines + (part == 0 ? header.newlines_before_rows : 0)) : 0;
  counts[kNulColumn] = rows.nul ? rows.nul->column : 0;
  counts[kRows] = static_cast<double>(parser.record().rows());
  counts[kLines] = parser.lines_read();
  counts[kNewlines] = static_cast<double>(rows.newlines + (part == 0 ? header.newlines_before_rows : 0));
  counts[kFrom] = static_cast<double>(from);
  counts[kTo] = static_cast<double>(to);
  counts[kRead] = static_cast<double>(rows.read);
  const auto append = [](std::vector<double>& left, const std::vector<double>& right) { left.insert(left.end(), right.begin(), right.end()); };
  if (auto c = share.merge(counts, append, false); c.outcome != PartShare::Outcome::combined)
    return diag::error("stopped", {}, c.why.empty() ? "another process stopped" : c.why);
  const auto at = [&](int k, Count f) { return counts[static_cast<std::size_t>(k) * kFields + f]; };

  // A file that changed while read: a part read fewer bytes than its range holds, or the last more.
  std::size_t read = header.rows_begin;
  bool changed = false;
  for (int k = 0; k < parts; ++k) {
    read += static_cast<std::size_t>(at(k, kRead));
    if (k + 1 < parts && at(k, kRead) != at(k, kTo) - at(k, kFrom)) changed = true;
  }
  if (changed || read != size) return data_diag::changed_while_read(path, changed_while_read(size, read).reason);
  double newlines_before = 0, lines_before = 0;
  for (int k = 0; k < parts; ++k) {
    if (at(k, kNul) != 0)
      return data_diag::binary_file(path, static_cast<int>(1 + newlines_before + at(k, kNulNewlines)), static_cast<int>(at(k, kNulColumn)));
    newlines_before += at(k, kNewlines);
  }
  for (int k = 0; k < parts; ++k) {
    if (at(k, kProblem) != 0) {
      // Parsed again here, its lines numbered as in the file, so that every part names the problem
      // as one process does.
      CsvParser again(std::string_view(), path, options);
      if (auto h = read_header(file, path, again); h.failure || h.binary || h.problem) return read_csv_in_pieces(file, path, options);
      if (k > 0) again.restart_lines(1 + static_cast<int>(lines_before));
      CsvOptions quiet = options;
      quiet.progress = nullptr;
      RowsRead redo = read_rows(file, path, again, static_cast<std::size_t>(at(k, kFrom)), static_cast<std::size_t>(at(k, kTo)), false, true, quiet);
      if (redo.failure) return *redo.failure;
      if (redo.problem) return *redo.problem;
      return data_diag::changed_while_read(path, "its rows read differently the second time");
    }
    lines_before += at(k, kLines);
  }

  // The columns, in part order, and the bookkeeping shifted by the rows and lines before.
  Record& record = parser.record();
  std::vector<std::size_t> lengths(static_cast<std::size_t>(parts));
  std::size_t total = 0;
  for (int k = 0; k < parts; ++k) total += lengths[static_cast<std::size_t>(k)] = static_cast<std::size_t>(at(k, kRows));
  std::vector<double> bookkeeping = bookkeeping_state(record.rows(), parser.lines_read(), record.first_faults, record.line_jumps);
  const auto join = [](std::vector<double>& left, const std::vector<double>& right) {
    Bookkeeping l = bookkeeping_of(left), r = bookkeeping_of(right);
    csv::append_later_rows(l.faults, l.jumps, l.rows, l.lines, std::move(r.faults), r.jumps);
    left = bookkeeping_state(l.rows + r.rows, l.lines + r.lines, l.faults, l.jumps);
  };
  if (auto c = share.merge(bookkeeping, join, false); c.outcome != PartShare::Outcome::combined)
    return diag::error("stopped", {}, c.why.empty() ? "another process stopped" : c.why);
  Bookkeeping whole = bookkeeping_of(bookkeeping);
  record.first_faults = std::move(whole.faults);
  record.line_jumps = std::move(whole.jumps);
  for (auto& column : record.columns) {
    std::vector<double> all(total);
    share.concatenate(column, all, lengths);
    column = Column(std::move(all));
  }
  return parser.finish();
}

}  // namespace

std::variant<Record, Diagnostic> read_csv(const std::string& path, const CsvOptions& options) {
  // Read, not mapped (diagnostics/regular_file.hpp): a file truncated while it is read gives an
  // error, never SIGBUS; a FIFO or a device (/dev/zero) is refused before a byte is read.
  auto opened = open_regular_file(path);
  if (auto* refusal = std::get_if<FileRefusal>(&opened)) return refused(path, *refusal);
  const OpenFile& file = std::get<OpenFile>(opened);
  if (options.share && options.share->parts() > 1) return read_csv_by_parts(file, path, options);
  if (options.chunk_bytes > 0 && file.size() > options.chunk_bytes) return read_csv_in_pieces(file, path, options);
  auto read = read_open_file(file.descriptor(), file.size());
  if (auto* refusal = std::get_if<FileRefusal>(&read)) return refused(path, *refusal);
  const auto& bytes = std::get<FileBytes>(read);
  return parse_csv(std::string_view(bytes.data.get(), bytes.size), path, options);
}

}  // namespace sidc
