// The CSV parser (csv_parser.hpp): the cells, the header, the rows, on one thread or two.
#include "runtime/records/csv_parser.hpp"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fmt/format.h>
#include <memory>
#include <system_error>
#include <thread>
#include <unordered_map>

namespace sidc::csv {
namespace {

constexpr std::size_t kFaultTextKept = 64;

// A faulty cell is a quiet NaN whose low payload bits hold the CellFault; copying a vector keeps
// the bits, so the fault survives row selection and can still be named when the column is used.
constexpr std::uint64_t kFaultTag = 0x7ff8'5c0d'0000'0000ull;  // quiet NaN with a recognisable tag

double faulty_value(CellFault fault) {
  return std::bit_cast<double>(kFaultTag | static_cast<std::uint64_t>(fault));
}

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

}  // namespace

// The bookkeeping of rows parsed apart (a second thread's, another process's) put after the rows
// before them: `later`'s rows are numbered from 0 and its lines from 1; the `rows` and `lines`
// before them shift both. Each column keeps its first kFaultsKeptPerColumn faulty cells.
std::optional<NulByte> first_nul(const char* floor, const char* first, const char* last) {
  const void* nul = std::memchr(first, '\0', static_cast<std::size_t>(last - first));
  if (!nul) return std::nullopt;
  const char* at = static_cast<const char*>(nul);
  const char* line_start = at;
  while (line_start > floor && *(line_start - 1) != '\n') --line_start;
  return NulByte{static_cast<std::size_t>(std::count(first, at, '\n')), static_cast<int>(at - line_start) + 1};
}

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
  if (const auto nul = first_nul(begin(), begin(), end())) return data_diag::binary_file(path_, static_cast<int>(1 + nul->newlines), nul->column);
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

}  // namespace sidc::csv

namespace sidc {

CellFault cell_fault(double value) {
  if (!std::isnan(value)) return CellFault::none;
  const auto bits = std::bit_cast<std::uint64_t>(value);
  if ((bits & ~std::uint64_t{0xff}) == csv::kFaultTag) {
    const auto code = static_cast<unsigned>(bits & 0xff);
    if (code > 0 && code <= static_cast<unsigned>(CellFault::out_of_range)) return static_cast<CellFault>(code);
  }
  return CellFault::not_a_number;  // a NaN made by arithmetic, not by the reader
}

std::variant<Record, Diagnostic> parse_csv(std::string_view text, const std::string& path, const CsvOptions& options) {
  csv::CsvParser parser(text, path, options);
  return parser.run();
}

}  // namespace sidc
