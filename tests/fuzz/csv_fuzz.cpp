// libFuzzer target: the CSV reader (runtime/records/csv_parser.cpp, parse_csv) on text in memory,
// and, on the same bytes written to a file, read_csv in pieces of a few bytes and by two parts
// (threads sharing through memory, as MPI ranks do: runtime/records/csv_file.cpp), which must give
// parse_csv's record or diagnostic. The first byte chooses the options (separator, header, decimal
// comma, comment character, one or two threads); the rest is the file.
//
// Relies on: records.hpp (parse_csv, read_csv, CsvOptions::is_valid), tests/support/thread_share.hpp.
// Guarantees: any bytes are either a record or a diagnostic, the same however they are read; a
// crash, a sanitizer report, a hang (-timeout) or a difference (a trap) is a finding.
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

#include <unistd.h>

#include "runtime/records/records.hpp"
#include "support/thread_share.hpp"

namespace {

// Everything a read gives, bit for bit: the diagnostic's text, or the header line, names, values,
// faults and every row's line.
std::string described(const std::variant<sidc::Record, sidc::Diagnostic>& result) {
  if (const auto* d = std::get_if<sidc::Diagnostic>(&result)) return "diagnostic: " + sidc::render(*d);
  const sidc::Record& r = std::get<sidc::Record>(result);
  std::string out = std::to_string(r.header_line) + ":";
  for (std::size_t c = 0; c < r.names.size(); ++c) {
    out += r.names[c] + "=";
    for (double v : r.columns[c]) out += std::to_string(std::bit_cast<std::uint64_t>(v)) + ",";
    for (const auto& f : r.first_faults[c]) out += "(" + std::to_string(f.row) + " " + std::to_string(static_cast<int>(f.fault)) + " " + f.text + ")";
  }
  for (std::size_t row = 0; row < r.rows(); ++row) out += " " + std::to_string(r.line_of_row(row));
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const unsigned choice = data[0];
  sidc::CsvOptions options;
  constexpr char separators[] = {0, ',', ';', '\t', ' ', 0, ',', ';'};
  options.separator = separators[choice & 7u];
  options.header = static_cast<sidc::CsvOptions::Header>((choice >> 3) % 3);
  options.decimal_comma = (choice & 0x20u) != 0;
  options.comment = (choice & 0x40u) ? 0 : '#';
  // Two threads from 64 bytes on: the split at a line start is fuzzed too.
  options.parallel_above_bytes = (choice & 0x80u) ? 64 : SIZE_MAX;
  if (!options.is_valid()) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  // The same bytes also from a file in the current folder, one per process; diagnostics name it.
  static const std::string path = "fuzz-" + std::to_string(::getpid()) + ".csv";
  const std::string expected = described(sidc::parse_csv(text, path, options));

  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    if (std::fclose(f) != 0 || !written) return 0;
  } else {
    return 0;
  }
  sidc::CsvOptions pieces = options;
  pieces.chunk_bytes = 1 + (choice >> 4) % 7;  // 1 to 7 bytes: a piece end on every kind of byte
  if (described(sidc::read_csv(path, pieces)) != expected) __builtin_trap();
  sidc::ThreadRoom room(2);
  const auto parts = sidc::in_parts(room, [&](sidc::RowShare& share, int) {
    sidc::CsvOptions mine = pieces;
    mine.share = &share;
    return described(sidc::read_csv(path, mine));
  });
  for (const auto& part : parts)
    if (part != expected) __builtin_trap();
  std::remove(path.c_str());
  return 0;
}
