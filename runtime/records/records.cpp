// CSV reading: a file up to CsvOptions::chunk_bytes read whole into one buffer sized from the
// file, a larger one in pieces that end at line ends (read_csv_in_pieces: the text is never held
// whole), never mapped (a file truncated while mapped ends the process with SIGBUS;
// diagnostics/regular_file.hpp); then one pass over the bytes of each, on two threads for large
// ones (the second half from a line start near the middle; see parse_rows_on_two_threads). The
// fast path per cell
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
#include <fmt/format.h>
#include <memory>
#include <new>
#include <system_error>
#include <thread>
#include <unordered_map>

#include "diagnostics/regular_file.hpp"

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
  const int line_offset = line_ - 1;  // tail line 1 is file line line_
  for (std::size_t j = 0; j < record_.columns.size(); ++j) {
    auto& column = record_.columns[j];
    column.insert(column.end(), tail.record_.columns[j].begin(), tail.record_.columns[j].end());
    auto& kept = record_.first_faults[j];
    for (auto& fault : tail.record_.first_faults[j]) {
      if (kept.size() >= kFaultsKeptPerColumn) break;
      fault.row += head_rows;
      kept.push_back(std::move(fault));
    }
  }
  for (const auto& [row, line] : tail.record_.line_jumps) {
    const std::size_t shifted_row = row + head_rows;
    const int shifted_line = line + line_offset;
    // The tail's first row always starts a jump of its own; keep it only when it is one.
    if (shifted_row > 0 && record_.line_of_original_row(shifted_row - 1) + 1 == shifted_line &&
        !record_.line_jumps.empty() && row == 0)
      continue;
    record_.line_jumps.emplace_back(shifted_row, shifted_line);
  }
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

// A file larger than CsvOptions::chunk_bytes, read and parsed piece by piece: each piece ends at
// its last line end (a line longer than a piece grows the buffer), so memory is a piece, not the
// file. Every answer is the whole file's: a file that changed while read is refused first, a NUL
// byte anywhere next (the rest is still read for both), then the first parse problem.
std::variant<Record, Diagnostic> read_csv_in_pieces(const OpenFile& file, const std::string& path, const CsvOptions& options) {
  if (std::string why; !options.is_valid(&why)) return data_diag::invalid_csv_options(why);
  std::size_t capacity = 2 * options.chunk_bytes;
  std::unique_ptr<char[]> buffer(new (std::nothrow) char[capacity]);
  if (!buffer) return data_diag::cannot_open(path, fmt::format("not enough memory for a piece of {} bytes", capacity));
  CsvParser parser(std::string_view(), path, options);
  std::size_t read = 0, held = 0;   // bytes read from the file; of them, still in the buffer
  std::size_t newlines_before = 0;  // in the bytes already given up (for a NUL's row)
  bool started = false, at_end = false;
  std::optional<Diagnostic> binary, problem;
  while (!at_end || held > 0) {
    if (!at_end) {
      if (held == capacity) {  // a line longer than the buffer: double it
        std::unique_ptr<char[]> larger(new (std::nothrow) char[2 * capacity]);
        if (!larger) return data_diag::cannot_open(path, fmt::format("not enough memory for a line of over {} bytes", capacity));
        std::memcpy(larger.get(), buffer.get(), held);
        buffer = std::move(larger);
        capacity *= 2;
      }
      const long long got = file.read_at(buffer.get() + held, read, capacity - held);
      if (got < 0) return data_diag::cannot_open(path, std::strerror(static_cast<int>(-got)));
      if (!binary)
        if (const void* nul = std::memchr(buffer.get() + held, '\0', static_cast<std::size_t>(got))) {
          const char* at = static_cast<const char*>(nul);
          const char* line_start = at;
          while (line_start > buffer.get() && *(line_start - 1) != '\n') --line_start;
          const auto row = 1 + newlines_before + static_cast<std::size_t>(std::count(static_cast<const char*>(buffer.get()), at, '\n'));
          binary = data_diag::binary_file(path, static_cast<int>(row), static_cast<int>(at - line_start) + 1);
        }
      at_end = got == 0;
      read += static_cast<std::size_t>(got);
      held += static_cast<std::size_t>(got);
      if (read > file.size()) break;  // grown: refused below
    }
    // The piece: up to the last line end (everything at the end of the file).
    std::size_t cut = held;
    if (!at_end) {
      const char* last = buffer.get() + held;
      while (last > buffer.get() && *(last - 1) != '\n') --last;
      cut = static_cast<std::size_t>(last - buffer.get());
      if (cut == 0) continue;  // no whole line yet
    }
    const std::string_view piece(buffer.get(), cut);
    if (!binary && !problem) {
      parser.set_text(piece);
      if (!started) {
        if (!at_end && !parser.holds_first_line(piece)) continue;  // blank and comment lines only so far: read on
        const char* p = nullptr;
        problem = parser.begin_text(p);
        if (!problem) {
          parser.reserve_rows(p, file.size() - (read - held) - static_cast<std::size_t>(p - piece.data()));
          problem = parser.rows_of_text(p);
        }
        started = true;
      } else {
        problem = parser.rows_of_text(piece.data());
      }
    }
    if (!binary) newlines_before += static_cast<std::size_t>(std::count(piece.begin(), piece.end(), '\n'));
    if (options.progress) options.progress(std::min(read, file.size()), file.size());
    std::memmove(buffer.get(), buffer.get() + cut, held - cut);
    held -= cut;
  }
  if (read != file.size()) return data_diag::changed_while_read(path, changed_while_read(file.size(), read).reason);
  if (binary) return *binary;
  if (problem) return *problem;
  if (!started) return data_diag::empty_file(path);
  return parser.finish();
}

}  // namespace

std::variant<Record, Diagnostic> read_csv(const std::string& path, const CsvOptions& options) {
  // Read, not mapped (diagnostics/regular_file.hpp): a file truncated while it is read gives an
  // error, never SIGBUS; a FIFO or a device (/dev/zero) is refused before a byte is read.
  auto opened = open_regular_file(path);
  if (auto* refusal = std::get_if<FileRefusal>(&opened)) return refused(path, *refusal);
  const OpenFile& file = std::get<OpenFile>(opened);
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
