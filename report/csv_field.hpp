// One field of a CSV file sidc writes (residuals.csv, local.csv, a simulation's CSV), as RFC 4180
// has it: as it is, or quoted with its quotes doubled when it holds a comma, a quote or a line end
// (a record path or a column name can hold any of them).
#pragma once

#include <string>

namespace sidc {

inline std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace sidc
