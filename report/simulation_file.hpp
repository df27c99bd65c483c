// The CSV that `sidc simulate` writes: the time column and each output under the column names the
// model binds them to, so a simulated record reads back like the recorded one.
#pragma once

#include <string>

#include "ir/ir.hpp"
#include "runtime/simulate/simulate.hpp"

namespace sidc {

// The column an output (or "t") is bound to in the model's data statements, else `fallback`.
std::string bound_column(const ir::Model& model, const std::string& signal, const std::string& fallback);

// `time_column` first, then one column per output; numbers in fmt's shortest round-trip form.
std::string simulation_csv(const ir::Model& model, const std::string& time_column, const SimulationSummary& summary);

}  // namespace sidc
