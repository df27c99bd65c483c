// The CSV parser behind read_csv and parse_csv (records.hpp), inside runtime/records only: text in,
// a Record or its first problem out, in one pass over the bytes (csv_parser.cpp); csv_file.cpp feeds
// it a file piece by piece, or one byte range per process. The fast path per cell reads the number
// straight off the buffer (read_simple_number, else std::from_chars; both stop at the separator by
// themselves), so a cell costs one conversion and a comparison; everything unusual (quotes, `+`,
// `D` exponents, decimal commas, text, NaN) falls to a slow path that looks at the cell's text.
// Large texts are parsed on two threads (the second half from a line start near the middle; see
// parse_rows_on_two_threads). Measured on a 10^7-row, 4-column, 426 MB file (2-core VM, -O2):
// about 28 M values/s and 300 MB/s in CPU time for read_csv, 34 M values/s for parse_csv on text
// already in memory (one thread; the 10^7-row bench record's figures with two threads are in
// bench/README.md).
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "runtime/records/records.hpp"

namespace sidc::csv {

constexpr std::size_t kFaultsKeptPerColumn = 4;

inline bool is_blank(char c) { return c == ' ' || c == '\t'; }

inline bool is_line_end(char c) { return c == '\n' || c == '\r'; }

// The outcome of reading one cell's text.
struct CellValue {
  double value = 0;
  CellFault fault = CellFault::none;
};

// One field of a header line (or of a line split the slow way).
struct Field {
  std::string text;
  int column = 0;  // 1-based field index
  bool quoted = false;
};

// The bookkeeping of rows parsed apart (a second thread's, another process's) put after the rows
// before them: `later`'s rows are numbered from 0 and its lines from 1; the `rows` and `lines`
// before them shift both. Each column keeps its first kFaultsKeptPerColumn faulty cells.
void append_later_rows(std::vector<std::vector<FaultyCell>>& faults, std::vector<std::pair<std::size_t, int>>& jumps, std::size_t rows,
                       int lines, std::vector<std::vector<FaultyCell>> later_faults, const std::vector<std::pair<std::size_t, int>>& later_jumps);

// Where the first NUL byte in [first, last) is, if there is one (a binary file): the '\n' bytes
// from `first` up to it, and its 1-based column, counted from the line start found by looking back
// no further than `floor`.
struct NulByte {
  std::size_t newlines = 0;
  int column = 0;
};
std::optional<NulByte> first_nul(const char* floor, const char* first, const char* last);

class CsvParser {
 public:
  CsvParser(std::string_view text, const std::string& path, const CsvOptions& options)
      : text_(text), path_(path), options_(options) {}

  std::variant<Record, Diagnostic> run();

  // run() in three steps, for a file given piece by piece (read_csv_in_pieces): the first piece,
  // up to the first row (checks, header); rows of each piece; the record. A piece ends at a line end.
  std::optional<Diagnostic> begin_text(const char*& p);
  std::optional<Diagnostic> rows_of_text(const char* p);
  std::variant<Record, Diagnostic> finish();
  void set_text(std::string_view text) { text_ = text; }
  // Whether `text` holds the line begin_text looks for first (neither blank nor a comment), whole.
  bool holds_first_line(std::string_view text) const;
  void reserve_rows(const char* p, std::size_t remaining);
  // For a part of the file read apart (read_csv_by_parts): its lines numbered from `first_line`
  // (1: numbered within the part, shifted afterwards), and what it has read.
  void restart_lines(int first_line) {
    line_ = first_line;
    expected_line_ = 0;
  }
  int lines_read() const { return line_ - 1; }  // lines before the next one, counted from the first
  Record& record() { return record_; }

 private:
  // Line bookkeeping.
  const char* begin() const { return text_.data(); }
  const char* end() const { return text_.data() + text_.size(); }
  void skip_line_end(const char*& p) {
    if (p < end() && *p == '\r') ++p;
    if (p < end() && *p == '\n') ++p;
    ++line_;
  }
  void skip_to_line_end(const char*& p) {
    while (p < end() && !is_line_end(*p)) ++p;
  }
  void skip_inline_blanks(const char*& p) const {
    if (blank_separated_) {
      while (p < end() && is_blank(*p)) ++p;
    } else {
      while (p < end() && (*p == ' ' || (*p == '\t' && separator_ != '\t'))) ++p;
    }
  }
  bool is_skipped_line(const char* p) const {  // p after leading blanks
    return p == end() || is_line_end(*p) || (options_.comment != 0 && *p == options_.comment);
  }
  int column_of(const char* line_start, const char* p) const;  // 1-based field index of p

  std::optional<Diagnostic> split_header(const char*& p, std::vector<Field>& fields);
  char detect_separator(const char* p) const;
  std::optional<Diagnostic> parse_rows(const char* p);
  const char* split_point(const char* p) const;
  std::optional<Diagnostic> parse_rows_on_two_threads(const char* p, const char* split);
  CellValue slow_cell(const char*& p, std::string& text);

  std::string_view text_;
  const std::string& path_;
  CsvOptions options_;
  int line_ = 1;
  int expected_line_ = 0;  // the line the next row is on when no line is skipped (line_jumps)
  char separator_ = ',';
  bool blank_separated_ = false;
  Record record_;
  std::unique_ptr<CsvParser> tail_;  // parse_rows_on_two_threads' second parser
};

}  // namespace sidc::csv
