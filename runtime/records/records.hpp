// Records: the sampled signals of one data file (CSV), stored column by column.
//
// Relies on: nothing but the bytes of the file. Guarantees: read_csv never throws, crashes or
// hangs on any input (empty, binary, ragged, a 1 GB line); every problem becomes a Diagnostic
// located at `file:row:col` (row = 1-based line number in the file, col = 1-based field index).
//
// What it accepts (each choice is tested in tests/runtime/records_test.cpp):
// - Separator: comma, semicolon, or blanks (a run of spaces and tabs is one separator), detected
//   from the first non-comment line: `;` present -> semicolon, else `,` -> comma, else blanks.
//   A strict tab separator (one tab per field, so empty cells are possible) only when asked for.
// - A header line of names, quoted (`"V1"`, with `""` for a quote inside) or not. The first
//   line is a header when any field is quoted or is not a number. A file without a header
//   (first line numeric) gets the names c1, c2, ... (CsvOptions::header overrides detection).
//   An empty name in the header (a pandas index column) also becomes c<field index>.
// - LF, CRLF or CR line ends; a UTF-8 byte-order mark; `#` comment lines; blank lines; rows whose
//   every field is empty (",,,," lines that spreadsheets write) are skipped like blank lines.
// - A trailing separator on every line (silverbox, cascaded tanks): a trailing empty unnamed
//   header field is dropped, and a row may then end with one extra empty field.
// - Numbers as std::from_chars reads them (12, -0.5, .25, 760., 1.5E+03), plus a leading `+`,
//   a Fortran `D` exponent (1.5D+03) and quoted cells ("1.5"). Values below the smallest
//   subnormal read as zero.
//
// Cell problems are not file errors: an empty, NaN, infinite, non-numeric, decimal-comma or
// out-of-range cell is stored as a NaN that carries its fault, and is reported only when the
// column is used (complete_column), so an unused text column or the cascaded-tanks `Ts` column
// (a value on the first row only) does not stop a fit, and a time window can leave a bad row out.
// File errors are: cannot open, directory, empty, binary (NUL byte), no data rows, unterminated
// quote in the header, duplicate names, and rows with too many or too few fields.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "diagnostics/data_catalogue.hpp"
#include "runtime/records/column.hpp"
#include "runtime/records/part_share.hpp"

namespace sidc {

using data_diag::CellFault;

// A faulty cell as it is written down when read (up to a few per column, in row order).
struct FaultyCell {
  std::size_t row = 0;  // 0-based row of the record as read (before any selection)
  CellFault fault = CellFault::none;
  std::string text;  // the cell as written, at most 64 characters
};

struct Record {
  std::string path;                           // as given; shown in diagnostics
  std::vector<std::string> names;             // one per column
  std::vector<Column> columns;                // column-major, all of length rows() (owned, or borrowed: column.hpp)
  std::vector<std::vector<FaultyCell>> first_faults;  // per column: the first few faulty cells, with text
  int header_line = 0;                        // 1-based line of the header; 0 when there is none

  // Where each row came from, so that a diagnostic can name its line in the file after rows
  // have been selected (select_rows) or interpolated (resample_linear): see original_row().
  std::vector<std::pair<std::size_t, int>> line_jumps;  // (row as read, its line), where lines skip
  std::size_t origin_first = 0;
  std::size_t origin_stride = 1;
  std::vector<std::size_t> interpolated_from;  // after resampling: the row (as read) each row was
                                               // interpolated from, the earlier of its two neighbours

  std::size_t rows() const { return columns.empty() ? 0 : columns.front().size(); }
  std::optional<std::size_t> column_index(std::string_view name) const;
  const Column* column(std::string_view name) const;  // null when there is no such column
  bool is_resampled() const { return !interpolated_from.empty(); }
  // Row r of this record is row original_row(r) of the record as read: origin_first + r *
  // origin_stride, looked up in interpolated_from after resampling.
  std::size_t original_row(std::size_t row) const;
  int line_of_original_row(std::size_t original) const;  // 1-based line in the file
  int line_of_row(std::size_t row) const { return line_of_original_row(original_row(row)); }
  int field_of_column(std::size_t column) const { return static_cast<int>(column) + 1; }
};

struct CsvOptions {
  char separator = 0;  // 0 = detect; ',' ';' '\t' (strict, one tab per field) or ' ' (runs of blanks)
  enum class Header { detect, present, absent } header = Header::detect;
  bool decimal_comma = false;  // read `1,5` as 1.5; only with ';', '\t' or ' ' separators
  char comment = '#';          // a line whose first non-blank character is this is skipped; 0 = none
  // Rows' text at least this long is parsed on two threads (each half from a line start); the
  // record and every diagnostic are the same as on one thread. SIZE_MAX: always one thread.
  std::size_t parallel_above_bytes = std::size_t{8} << 20;
  // read_csv reads a file larger than this in pieces of about this many bytes, each ending at a
  // line end (a longer line grows the piece), so that the file is never held whole; every answer,
  // record or diagnostic, is the whole file's. 0: always read whole.
  std::size_t chunk_bytes = std::size_t{16} << 20;
  // Called after each piece of a file read in pieces, with the bytes read and the file's size (a
  // progress line: cli/progress_line.hpp); read by parts (`share`), with the offset reached in
  // this part's byte range and the range's end. Never called for a file read whole.
  std::function<void(std::size_t bytes_read, std::size_t total)> progress;
  // Cooperating processes that read the file together (the ranks of `mpirun -np N sidc fit`, issue
  // 17; not owned): each reads and parses one byte range, from a line start, and every one ends with
  // the whole record, or the diagnostic, that one process reading the file alone gets. Null: alone.
  PartShare* share = nullptr;

  bool is_valid(std::string* why = nullptr) const;
};

// Reads a file (whole, or piece by piece above CsvOptions::chunk_bytes, or by the parts of
// CsvOptions::share, each its own byte range) and parses it.
std::variant<Record, Diagnostic> read_csv(const std::string& path, const CsvOptions& options = {});

// The same, on text already in memory; `path` is only used in diagnostics.
std::variant<Record, Diagnostic> parse_csv(std::string_view text, const std::string& path,
                                           const CsvOptions& options = {});

// The column `name` when every cell of it holds a finite number; otherwise the diagnostic for its
// first faulty cell, or for a name that is not in the header (with a did-you-mean hint).
std::variant<const Column*, Diagnostic> complete_column(const Record& record, std::string_view name);

// The fault a stored value carries (CellFault::none for every ordinary number).
CellFault cell_fault(double value);

}  // namespace sidc
