// Records (records.hpp): finding columns, the rows' lines in the file, the options' checks and the
// complete columns. Reading a file is csv_file.cpp's; parsing its text, csv_parser.cpp's.
#include "runtime/records/records.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace sidc {

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
