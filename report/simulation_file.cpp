#include "report/simulation_file.hpp"

#include <fmt/format.h>

#include "report/csv_field.hpp"

namespace sidc {

std::string bound_column(const ir::Model& model, const std::string& signal, const std::string& fallback) {
  for (const auto& d : model.data)
    for (const auto& [s, column] : d.bindings)
      if (s == signal) return column;
  return fallback;
}

std::string simulation_csv(const ir::Model& model, const std::string& time_column, const SimulationSummary& summary) {
  std::string csv = csv_field(time_column);
  for (const auto& name : summary.output_names) csv += "," + csv_field(bound_column(model, name, name));
  csv += "\n";
  for (std::size_t i = 0; i < summary.time.size(); ++i) {
    csv += fmt::format("{}", summary.time[i]);
    for (const auto& v : summary.outputs) csv += fmt::format(",{}", v[i]);
    csv += "\n";
  }
  return csv;
}

}  // namespace sidc
