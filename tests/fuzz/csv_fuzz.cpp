// libFuzzer target: the CSV reader (runtime/records/csv_parser.cpp, parse_csv) on text in memory.
// The first byte chooses the options (separator, header, decimal comma, comment character,
// one or two threads); the rest is the file.
//
// Relies on: records.hpp (parse_csv, CsvOptions::is_valid). Guarantees: any bytes are either a
// record or a diagnostic; a crash, a sanitizer report or a hang (-timeout) is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "runtime/records/records.hpp"

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
  (void)sidc::parse_csv(text, "fuzz.csv", options);
  return 0;
}
