// CSV reading: a file up to CsvOptions::chunk_bytes read whole into one buffer sized from the
// file, a larger one in pieces that end at line ends (read_csv_in_pieces: the text is never held
// whole), never mapped (a file truncated while mapped ends the process with SIGBUS;
// diagnostics/regular_file.hpp); then one pass over the bytes of each, on two threads for large
// ones (the second half from a line start near the middle; see parse_rows_on_two_threads). Under
// mpirun each process reads one byte range of the file and the parts are put together
// (read_csv_by_parts). The fast path per cell
// reads the number straight off the buffer (read_simple_number, else std::from_chars; both stop
// at the separator by themselves), so a cell costs one conversion and a comparison; everything
// unusual (quotes, `+`, `D` exponents, decimal commas, text, NaN) falls to a slow path that
// looks at the cell's text. Measured on a
// 10^7-row, 4-column, 426 MB file (2-core VM, -O2): about 28 M values/s and 300 MB/s in CPU
// time for read_csv, 34 M values/s for parse_csv on text already in memory (one thread; the
// 10^7-row bench record's figures with two threads are in bench/README.md).
#include "runtime/records/records.hpp"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <future>
#include <fmt/format.h>
#include <memory>
#include <new>
#include <system_error>
#include <thread>
#include <unordered_map>

#include "diagnostics/regular_file.hpp"
#include "runtime/records/part_share.hpp"

namespace sidc {
namespace {

constexpr std::size_t kFaultsKeptPerColumn = 4;
constexpr std::size_t kFaultTextKept = 64;

// A faulty cell is a quiet NaN whose low payload bits hold the CellFault; copying a vector keeps
// the bits, so the fault survives row selection and can still be named when the column is used.
constexpr std::uint64_t kFaultTag = 0x7ff8'5c0d'0000'0000ull;  // quiet NaN with a recognisable tag

double faulty_value(CellFault fault) {
  return std::bit_cast<double>(kFaultTag | static_cast<std::uint64_t>(fault));
}

bool is_blank(char c) { return c == ' ' || c == '\t'; }

// Decimal numbers the way CSV files write them (-12.345e-6), read in one pass. When the digits
// fit in 2^53 and the decimal exponent is within +-22, mantissa and power of ten are both exact
// doubles, so one multiplication or division is correctly rounded (Clinger's fast path) and the
// result is bit for bit what std::from_chars gives. Everything else (more digits, larger
// exponents, nan, inf, malformed text) goes to std::from_chars, which is several times slower
// in libstdc++ 12. Returns the end of the number, or null when std::from_chars must decide.
const char* read_simple_number(const char* p, const char* end, double& value) {
  static constexpr double kPowersOfTen[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                            1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                            1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  const bool negative = p < end && *p == '-';
  if (negative) ++p;
  // All digits go into the mantissa, leading zeros included; more than 19 of them may overflow
  // it, and then std::from_chars decides (so does a number such as 0.00000000000000000001).
  std::uint64_t mantissa = 0;
  const char* digits = p;
  for (; p < end && static_cast<unsigned>(*p - '0') < 10; ++p) mantissa = mantissa * 10 + static_cast<unsigned>(*p - '0');
  std::ptrdiff_t count = p - digits;
  int exponent = 0;
  if (p < end && *p == '.') {
    const char* fraction = ++p;
    for (; p < end && static_cast<unsigned>(*p - '0') < 10; ++p)
      mantissa = mantissa * 10 + static_cast<unsigned>(*p - '0');
    count += p - fraction;
    if (count > 19) return nullptr;
    exponent = -static_cast<int>(p - fraction);
  }
  if (count == 0 || count > 19) return nullptr;
  if (p < end && (*p == 'e' || *p == 'E')) {
    const char* q = p + 1;
    const bool negative_exponent = q < end && *q == '-';
    if (q < end && (*q == '-' || *q == '+')) ++q;
    if (q == end || static_cast<unsigned>(*q - '0') >= 10) return nullptr;  // `1e`: from_chars stops before e
    int written = 0;
    for (; q < end && static_cast<unsigned>(*q - '0') < 10; ++q) {
      if (written > 10000) return nullptr;
      written = written * 10 + (*q - '0');
    }
    exponent += negative_exponent ? -written : written;
    p = q;
  }
  if (mantissa > (std::uint64_t{1} << 53) || exponent < -22 || exponent > 22) return nullptr;
  double v = static_cast<double>(mantissa);
  v = exponent < 0 ? v / kPowersOfTen[-exponent] : v * kPowersOfTen[exponent];
  value = negative ? -v : v;
  return p;
}

bool is_line_end(char c) { return c == '\n' || c == '\r'; }

// The outcome of reading one cell's text.
struct CellValue {
  double value = 0;
  CellFault fault = CellFault::none;
};

bool parse_whole(std::string_view text, double& value, bool& out_of_range) {
  out_of_range = false;
  if (text.empty()) return false;
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (*first == '+' && text.size() > 1 && *(first + 1) != '-' && *(first + 1) != '+') ++first;
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (ptr != last) return false;
  if (ec == std::errc::result_out_of_range) {
    // from_chars leaves the value alone on both overflow and underflow; strtod tells them apart.
    const std::string copy(first, last);
    const double v = std::strtod(copy.c_str(), nullptr);
    if (std::isinf(v)) {
      out_of_range = true;
      return true;
    }
    value = v;  // underflow: zero or a subnormal, as strtod rounds it
    return true;
  }
  return ec == std::errc();
}

std::string_view trim_blanks(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

// The slow path: what the text of one (unquoted or already unquoted) cell means.
CellValue classify_cell(std::string_view text, bool decimal_comma) {
  text = trim_blanks(text);
  if (text.empty()) return {0, CellFault::empty};
  if (text.size() >= 2 && text.front() == '"' && text.back() == '"') {
    std::string inner(text.substr(1, text.size() - 2));
    return classify_cell(inner, decimal_comma);
  }
  double v = 0;
  bool out_of_range = false;
  if (parse_whole(text, v, out_of_range)) {
    if (out_of_range) return {0, CellFault::out_of_range};
    if (std::isnan(v)) return {0, CellFault::not_a_number};
    if (std::isinf(v)) return {0, CellFault::infinite};
    return {v, CellFault::none};
  }
  // A Fortran double-precision exponent: 1.5D+03.
  if (const auto d = text.find_first_of("dD"); d != std::string_view::npos && d > 0) {
    std::string copy(text);
    copy[d] = 'e';
    if (parse_whole(copy, v, out_of_range) && std::isfinite(v)) return {v, CellFault::none};
    if (out_of_range) return {0, CellFault::out_of_range};
  }
  // One comma where the decimal point belongs.
  if (const auto c = text.find(','); c != std::string_view::npos && text.find(',', c + 1) == std::string_view::npos) {
    std::string copy(text);
    copy[c] = '.';
    if (parse_whole(copy, v, out_of_range) && std::isfinite(v)) {
      if (decimal_comma) return {v, CellFault::none};
      return {0, CellFault::decimal_comma};
    }
  }
  return {0, CellFault::non_numeric};
}

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
                       int lines, std::vector<std::vector<FaultyCell>> later_faults, const std::vector<std::pair<std::size_t, int>>& later_jumps) {
  for (std::size_t j = 0; j < faults.size() && j < later_faults.size(); ++j) {
    auto& kept = faults[j];
    for (auto& fault : later_faults[j]) {
      if (kept.size() >= kFaultsKeptPerColumn) break;
      fault.row += rows;
      kept.push_back(std::move(fault));
    }
  }
  for (const auto& [row, line] : later_jumps) {
    const std::size_t shifted_row = row + rows;
    const int shifted_line = line + lines;
    // The later rows' first row always starts a jump of its own; keep it only when it is one (the
    // row before it, the last before them, lies on the line before).
    if (row == 0 && shifted_row > 0 && !jumps.empty() &&
        jumps.back().second + static_cast<int>(shifted_row - 1 - jumps.back().first) + 1 == shifted_line)
      continue;
    jumps.emplace_back(shifted_row, shifted_line);
  }
}

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

char CsvParser::detect_separator(const char* p) const {
  bool in_quotes = false;
  bool comma = false;
  bool semicolon = false;
  for (; p < end() && !is_line_end(*p); ++p) {
    if (*p == '"') in_quotes = !in_quotes;
    if (in_quotes) continue;
    if (*p == ';') semicolon = true;
    if (*p == ',') comma = true;
  }
  // A semicolon file may well hold decimal commas; a comma file rarely holds a semicolon.
  if (semicolon) return ';';
  if (comma) return ',';
  return ' ';
}

int CsvParser::column_of(const char* line_start, const char* p) const {
  // Only called on error paths: count the separators before p, quotes respected.
  int column = 1;
  bool in_quotes = false;
  const char* q = line_start;
  if (blank_separated_) {
    while (q < p && is_blank(*q)) ++q;
    bool in_blank = false;
    for (; q < p; ++q) {
      if (*q == '"') in_quotes = !in_quotes;
      if (in_quotes) continue;
      if (is_blank(*q)) {
        in_blank = true;
      } else if (in_blank) {
        ++column;
        in_blank = false;
      }
    }
    return column;
  }
  for (; q < p; ++q) {
    if (*q == '"') in_quotes = !in_quotes;
    if (!in_quotes && *q == separator_) ++column;
  }
  return column;
}

// Splits the line at p into fields, quotes honoured; leaves p at the line end.
std::optional<Diagnostic> CsvParser::split_header(const char*& p, std::vector<Field>& fields) {
  const char* line_start = p;
  int column = 1;
  for (;;) {
    skip_inline_blanks(p);
    Field field;
    field.column = column;
    if (p < end() && *p == '"') {
      const char* quote = p;
      field.quoted = true;
      ++p;
      for (;;) {
        if (p == end() || is_line_end(*p))
          return data_diag::unterminated_quote(path_, line_, column_of(line_start, quote));
        if (*p == '"') {
          if (p + 1 < end() && *(p + 1) == '"') {
            field.text += '"';
            p += 2;
            continue;
          }
          ++p;
          break;
        }
        field.text += *p++;
      }
      // Anything after the closing quote up to the separator belongs to the field (lenient).
      while (p < end() && !is_line_end(*p) && !(blank_separated_ ? is_blank(*p) : *p == separator_)) field.text += *p++;
    } else {
      while (p < end() && !is_line_end(*p) && !(blank_separated_ ? is_blank(*p) : *p == separator_)) field.text += *p++;
    }
    if (!field.quoted) field.text = std::string(trim_blanks(field.text));
    fields.push_back(std::move(field));
    skip_inline_blanks(p);
    if (p == end() || is_line_end(*p)) break;
    if (!blank_separated_) ++p;  // the separator
    ++column;
    if (blank_separated_) {
      skip_inline_blanks(p);
      if (p == end() || is_line_end(*p)) break;
    }
  }
  return std::nullopt;
}

void CsvParser::reserve_rows(const char* p, std::size_t remaining) {
  // Estimate the row count of the `remaining` bytes (from p on, in this text and beyond) from the
  // first 64 KiB, so that the columns grow without copying.
  const std::size_t sample = std::min<std::size_t>({remaining, std::size_t{1} << 16, static_cast<std::size_t>(end() - p)});
  const auto lines = static_cast<std::size_t>(std::count(p, p + sample, '\n'));
  if (sample == 0 || lines == 0) return;
  const std::size_t estimate = remaining / sample * lines + remaining % sample * lines / sample + 16;
  const std::size_t capped = std::min<std::size_t>(estimate + estimate / 16, remaining / 2 + 16);
  for (auto& column : record_.columns) column.reserve(capped);
}

// A cell the fast path did not take: find its extent (quotes honoured), then classify its text.
CellValue CsvParser::slow_cell(const char*& p, std::string& text) {
  text.clear();
  if (p < end() && *p == '"') {
    ++p;
    while (p < end() && !is_line_end(*p)) {
      if (*p == '"') {
        if (p + 1 < end() && *(p + 1) == '"') {
          text += '"';
          p += 2;
          continue;
        }
        ++p;
        break;
      }
      text += *p++;
    }
    while (p < end() && !is_line_end(*p) && !(blank_separated_ ? is_blank(*p) : *p == separator_)) text += *p++;
    const CellValue inner = classify_cell(text, options_.decimal_comma || separator_ != ',');
    // In a comma file a decimal comma must have been quoted; reading it needs the option.
    if (inner.fault == CellFault::none && separator_ == ',' && !options_.decimal_comma &&
        text.find(',') != std::string::npos)
      return {0, CellFault::decimal_comma};
    return inner;
  }
  while (p < end() && !is_line_end(*p) && !(blank_separated_ ? is_blank(*p) : *p == separator_)) text += *p++;
  return classify_cell(text, options_.decimal_comma);
}

std::optional<Diagnostic> CsvParser::parse_rows(const char* p) {
  const std::size_t n = record_.names.size();
  auto& columns = record_.columns;
  std::vector<std::size_t> faults_this_row;  // columns that recorded a fault text on this row
  std::string cell_text;
  std::size_t row = columns.empty() ? 0 : columns.front().size();  // rows already read (a continued parse)
  const char sep = separator_;
  const bool blanks = blank_separated_;

  while (p < end()) {
    const char* line_start = p;
    skip_inline_blanks(p);
    if (is_skipped_line(p)) {
      skip_to_line_end(p);
      skip_line_end(p);
      continue;
    }
    const int row_line = line_;
    std::size_t empty_cells = 0;
    faults_this_row.clear();
    for (std::size_t j = 0; j < n; ++j) {
      if (j > 0) skip_inline_blanks(p);
      const char* cell_start = p;
      double v = 0;
      const char* q = read_simple_number(p, end(), v);
      bool fast = q != nullptr;
      if (!fast) {
        const auto [r, ec] = std::from_chars(p, end(), v);
        q = r;
        fast = ec == std::errc() && std::isfinite(v);
      }
      const char* after = q;
      if (fast) {
        while (after < end() && is_blank(*after) && !(sep == '\t' && *after == '\t')) ++after;
        fast = after == end() || is_line_end(*after) || (!blanks && *after == sep) || (blanks && after > q);
      }
      CellFault fault = CellFault::none;
      if (fast) {
        p = after;
      } else {
        p = cell_start;
        const CellValue cell = slow_cell(p, cell_text);
        v = cell.value;
        fault = cell.fault;
        skip_inline_blanks(p);
      }
      if (fault != CellFault::none) {
        if (fault == CellFault::empty) ++empty_cells;
        v = faulty_value(fault);
        auto& kept = record_.first_faults[j];
        if (kept.size() < kFaultsKeptPerColumn) {
          kept.push_back({row, fault, cell_text.substr(0, kFaultTextKept)});
          faults_this_row.push_back(j);
        }
      }
      columns[j].push_back(v);

      const bool at_line_end = p == end() || is_line_end(*p);
      if (j + 1 < n) {
        if (at_line_end)
          return data_diag::too_few_fields(path_, row_line, static_cast<int>(j) + 2, j + 1, n, blanks);
        if (!blanks) ++p;  // the separator
      } else if (!at_line_end) {
        // A trailing separator followed by nothing (silverbox, cascaded tanks) is allowed.
        const char* r = p;
        if (!blanks && *r == sep) {
          ++r;
          skip_inline_blanks(r);
        }
        if (blanks || !(r == end() || is_line_end(*r)))
          return data_diag::too_many_fields(path_, row_line, column_of(line_start, p) + 1, n,
                                            blanks);
        p = r;
      }
    }
    skip_line_end(p);
    if (empty_cells == n) {
      // A row of empty cells is a blank line written by a spreadsheet, not a sample.
      for (auto& column : columns) column.pop_back();
      for (std::size_t j : faults_this_row) record_.first_faults[j].pop_back();
      continue;
    }
    if (row_line != expected_line_) record_.line_jumps.emplace_back(row, row_line);
    expected_line_ = row_line + 1;
    ++row;
  }
  return std::nullopt;
}

// Where a second thread may start: the first line start after the middle of the rows' text, when
// that text is at least CsvOptions::parallel_above_bytes long and the machine has a second core.
const char* CsvParser::split_point(const char* p) const {
  const auto remaining = static_cast<std::size_t>(end() - p);
  if (remaining < options_.parallel_above_bytes || remaining < 2 || std::thread::hardware_concurrency() < 2) return nullptr;
  const char* middle = p + remaining / 2;
  const void* newline = std::memchr(middle, '\n', static_cast<std::size_t>(end() - middle));
  if (!newline) return nullptr;  // CR-only line ends: one thread
  const char* split = static_cast<const char*>(newline) + 1;
  return split < end() ? split : nullptr;
}

// The rows before `split` here, the rows from `split` on a second parser on another thread (its
// line numbers counted from 1 and shifted afterwards), then its rows appended. When the second
// part has a problem, it is parsed again here, after the first, so that the diagnostic carries
// the line number of the file; the result is the same as parse_rows(p) in every case.
std::optional<Diagnostic> CsvParser::parse_rows_on_two_threads(const char* p, const char* split) {
  const std::string_view whole = text_;
  // The second parser is kept from piece to piece (read_csv_in_pieces): its columns' memory is
  // reused, not faulted in afresh for every piece.
  if (!tail_) tail_ = std::make_unique<CsvParser>(std::string_view(), path_, options_);
  CsvParser& tail = *tail_;
  tail.text_ = std::string_view(split, static_cast<std::size_t>(end() - split));
  tail.line_ = 1;
  tail.expected_line_ = 0;
  tail.separator_ = separator_;
  tail.blank_separated_ = blank_separated_;
  tail.record_.names = record_.names;
  tail.record_.line_jumps.clear();
  tail.record_.columns.resize(record_.columns.size());
  for (auto& column : tail.record_.columns) column.owned().clear();
  tail.record_.first_faults.assign(record_.first_faults.size(), {});
  tail.reserve_rows(split, static_cast<std::size_t>(end() - split));
  std::optional<Diagnostic> tail_error;
  std::thread second([&] { tail_error = tail.parse_rows(split); });
  text_ = std::string_view(whole.data(), static_cast<std::size_t>(split - whole.data()));
  std::optional<Diagnostic> head_error = parse_rows(p);
  second.join();
  text_ = whole;
  if (head_error) return head_error;
  if (tail_error) return parse_rows(split);  // line_ is where the first part ended: the file's numbering
  const std::size_t head_rows = record_.rows();
  for (std::size_t j = 0; j < record_.columns.size(); ++j) {
    auto& column = record_.columns[j];
    column.insert(column.end(), tail.record_.columns[j].begin(), tail.record_.columns[j].end());
  }
  append_later_rows(record_.first_faults, record_.line_jumps, head_rows, line_ - 1, std::move(tail.record_.first_faults),
                    tail.record_.line_jumps);
  line_ += tail.line_ - 1;
  return std::nullopt;
}

std::variant<Record, Diagnostic> CsvParser::run() {
  const char* p = nullptr;
  if (auto error = begin_text(p)) return *error;
  reserve_rows(p, static_cast<std::size_t>(end() - p));
  if (auto error = rows_of_text(p)) return *error;
  return finish();
}

bool CsvParser::holds_first_line(std::string_view text) const {
  const char* p = text.data();
  const char* stop = text.data() + text.size();
  if (text.size() >= 3 && std::memcmp(p, "\xEF\xBB\xBF", 3) == 0) p += 3;
  while (p < stop) {
    while (p < stop && is_blank(*p)) ++p;
    const char* line_end = p;
    while (line_end < stop && !is_line_end(*line_end)) ++line_end;
    if (line_end == stop) return false;  // not a whole line yet
    if (p < line_end && !(options_.comment != 0 && *p == options_.comment)) return true;
    p = line_end + 1;
  }
  return false;
}

std::optional<Diagnostic> CsvParser::begin_text(const char*& p) {
  if (std::string why; !options_.is_valid(&why)) return data_diag::invalid_csv_options(why);
  record_.path = path_;
  if (text_.empty()) return data_diag::empty_file(path_);
  if (const void* nul = std::memchr(text_.data(), '\0', text_.size())) {
    const char* at = static_cast<const char*>(nul);
    const auto row = 1 + std::count(begin(), at, '\n');
    const char* line_start = at;
    while (line_start > begin() && *(line_start - 1) != '\n') --line_start;
    return data_diag::binary_file(path_, static_cast<int>(row), static_cast<int>(at - line_start) + 1);
  }
  p = begin();
  if (text_.size() >= 3 && std::memcmp(p, "\xEF\xBB\xBF", 3) == 0) p += 3;  // UTF-8 byte-order mark

  // The first line that is neither blank nor a comment: the header, or the first row.
  for (;;) {
    const char* q = p;
    while (q < end() && is_blank(*q)) ++q;
    if (q == end()) return data_diag::empty_file(path_);
    if (!is_skipped_line(q)) break;
    skip_to_line_end(q);
    skip_line_end(q);
    p = q;
  }

  separator_ = options_.separator != 0 ? options_.separator : detect_separator(p);
  blank_separated_ = separator_ == ' ';

  const char* first_line = p;
  const int first_line_number = line_;
  std::vector<Field> fields;
  if (auto error = split_header(p, fields)) return *error;
  // A trailing separator leaves an empty unnamed last field; it is not a column.
  if (!blank_separated_ && fields.size() > 1 && fields.back().text.empty() && !fields.back().quoted) fields.pop_back();

  bool has_header = options_.header == CsvOptions::Header::present;
  if (options_.header == CsvOptions::Header::detect) {
    for (const auto& f : fields)
      if (f.quoted || classify_cell(f.text, options_.decimal_comma).fault == CellFault::non_numeric) has_header = true;
  }

  const std::size_t n = fields.size();
  record_.columns.resize(n);
  record_.first_faults.resize(n);
  if (has_header) {
    record_.header_line = first_line_number;
    // Each name looked up among those before it in a hash map (a header of 300,000 names, compared
    // pair by pair, took over 20 s). The views point into record_.names, reserved so none moves.
    record_.names.reserve(n);
    std::unordered_map<std::string_view, std::size_t> seen;
    seen.reserve(n);
    for (const auto& f : fields) {
      std::string name = f.text.empty() ? fmt::format("c{}", f.column) : f.text;
      if (const auto it = seen.find(name); it != seen.end())
        return data_diag::duplicate_column(path_, first_line_number, f.column, name, static_cast<int>(it->second) + 1);
      record_.names.push_back(std::move(name));
      seen.emplace(record_.names.back(), record_.names.size() - 1);
    }
    skip_line_end(p);
  } else {
    for (std::size_t k = 0; k < n; ++k) record_.names.push_back(fmt::format("c{}", k + 1));
    p = first_line;
    line_ = first_line_number;
  }

  return std::nullopt;
}

std::optional<Diagnostic> CsvParser::rows_of_text(const char* p) {
  if (const char* split = split_point(p)) return parse_rows_on_two_threads(p, split);
  return parse_rows(p);
}

std::variant<Record, Diagnostic> CsvParser::finish() {
  if (record_.rows() == 0) return data_diag::no_data_rows(path_, record_.header_line);
  // Giving back what the estimate overshot (up to a fifth when the first rows are the shortest)
  // would copy every column once more; only a far larger reserve is given back.
  for (auto& column : record_.columns)
    if (column.owned().capacity() > column.size() + column.size() / 4) column.shrink_to_fit();
  return std::move(record_);
}

}  // namespace

std::optional<std::size_t> Record::column_index(std::string_view name) const {
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) return k;
  return std::nullopt;
}

const Column* Record::column(std::string_view name) const {
  const auto k = column_index(name);
  return k ? &columns[*k] : nullptr;
}

std::size_t Record::original_row(std::size_t row) const {
  const std::size_t index = origin_first + row * origin_stride;
  if (interpolated_from.empty()) return index;
  return index < interpolated_from.size() ? interpolated_from[index] : interpolated_from.back();
}

int Record::line_of_original_row(std::size_t original) const {
  auto it = std::upper_bound(line_jumps.begin(), line_jumps.end(), original,
                             [](std::size_t r, const std::pair<std::size_t, int>& jump) { return r < jump.first; });
  if (it == line_jumps.begin()) return 0;  // no rows (never the case for a record read from a file)
  --it;
  return it->second + static_cast<int>(original - it->first);
}

bool CsvOptions::is_valid(std::string* why) const {
  auto fail = [&](const char* reason) {
    if (why) *why = reason;
    return false;
  };
  if (separator != 0 && separator != ',' && separator != ';' && separator != '\t' && separator != ' ')
    return fail("the separator must be ',', ';', a tab or ' ' (blanks)");
  if (decimal_comma && separator == ',') return fail("decimal commas need a separator other than ','");
  if (comment == '"' || (comment != 0 && comment == separator)) return fail("the comment character is ambiguous");
  return true;
}

CellFault cell_fault(double value) {
  if (!std::isnan(value)) return CellFault::none;
  const auto bits = std::bit_cast<std::uint64_t>(value);
  if ((bits & ~std::uint64_t{0xff}) == kFaultTag) {
    const auto code = static_cast<unsigned>(bits & 0xff);
    if (code > 0 && code <= static_cast<unsigned>(CellFault::out_of_range)) return static_cast<CellFault>(code);
  }
  return CellFault::not_a_number;  // a NaN made by arithmetic, not by the reader
}

std::variant<Record, Diagnostic> parse_csv(std::string_view text, const std::string& path, const CsvOptions& options) {
  CsvParser parser(text, path, options);
  return parser.run();
}

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
  if (const void* nul = std::memchr(prefix.data(), '\0', prefix.size())) {
    const char* at = static_cast<const char*>(nul);
    const char* line_start = at;
    while (line_start > prefix.data() && *(line_start - 1) != '\n') --line_start;
    const auto row = 1 + std::count(prefix.data(), at, '\n');
    out.binary = data_diag::binary_file(path, static_cast<int>(row), static_cast<int>(at - line_start) + 1);
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
  bool nul = false;                   // a NUL byte among them; the first one's
  std::size_t nul_newlines = 0;       //   '\n' bytes before it (from `from` on)
  int nul_column = 0;                 //   and column
};

// One read into `buffer` after the `held` bytes it keeps, and what read_rows notes of the new
// bytes: the line ends among them, and a NUL byte (the line ends before it, its column).
struct Refill {
  long long got = 0;  // bytes read, or -errno
  std::size_t newlines = 0;
  bool nul = false;
  std::size_t nul_newlines = 0;
  int nul_column = 0;
};

Refill refill(const OpenFile& file, char* buffer, std::size_t held, std::size_t want, std::size_t offset, bool look_for_nul) {
  Refill r;
  r.got = want > 0 ? file.read_at(buffer + held, offset, want) : 0;
  if (r.got <= 0) return r;
  const char* first = buffer + held;
  const char* last = first + r.got;
  const void* nul = look_for_nul ? std::memchr(first, '\0', static_cast<std::size_t>(r.got)) : nullptr;
  if (!nul) {
    r.newlines = static_cast<std::size_t>(std::count(first, last, '\n'));
    return r;
  }
  const char* at = static_cast<const char*>(nul);
  const char* line_start = at;
  while (line_start > buffer && *(line_start - 1) != '\n') --line_start;
  r.nul = true;
  r.nul_newlines = static_cast<std::size_t>(std::count(first, at, '\n'));
  r.nul_column = static_cast<int>(at - line_start) + 1;
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
    if (!out.nul && r.nul) {
      out.nul = true;
      out.nul_newlines = out.newlines + r.nul_newlines;
      out.nul_column = r.nul_column;
    }
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
  if (rows.nul) return data_diag::binary_file(path, static_cast<int>(1 + newlines_before + rows.nul_newlines), rows.nul_column);
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
  counts[kNulNewlines] = static_cast<double>(rows.nul_newlines + (part == 0 ? header.newlines_before_rows : 0));
  counts[kNulColumn] = rows.nul_column;
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
    append_later_rows(l.faults, l.jumps, l.rows, l.lines, std::move(r.faults), r.jumps);
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

std::variant<const Column*, Diagnostic> complete_column(const Record& record, std::string_view name) {
  const auto k = record.column_index(name);
  if (!k) return data_diag::unknown_column(record.path, record.header_line, name, record.names);
  const auto& values = record.columns[*k];
  const auto bad = std::find_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); });
  if (bad == values.end()) return &values;
  const auto row = static_cast<std::size_t>(bad - values.begin());
  std::size_t original = record.original_row(row);
  auto known = [&](std::size_t r) -> const FaultyCell* {
    for (const auto& cell : record.first_faults[*k])
      if (cell.row == r) return &cell;
    return nullptr;
  };
  // An interpolated row copies the fault of either neighbour; name the one that is faulty.
  if (record.is_resampled() && !known(original) && known(original + 1)) ++original;
  const FaultyCell* cell = known(original);
  const CellFault fault = std::isinf(*bad) ? CellFault::infinite : cell_fault(*bad);
  return data_diag::bad_cell(record.path, record.line_of_original_row(original), record.field_of_column(*k),
                             record.names[*k], fault, cell ? std::string_view(cell->text) : std::string_view());
}

}  // namespace sidc
