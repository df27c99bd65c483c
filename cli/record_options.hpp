// The options `sidc fit` and `sidc select` share: which records to read (`--data`) and how to
// evaluate the model on them (driver/record_settings.hpp's RecordSettings, one option per field).
//
// Relies on: CLI11. Guarantees: the same option names, help and checks in both commands; what the
// values mean is driver/record_settings.hpp's, shared with the Python module.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "driver/record_settings.hpp"

namespace sidc {

struct RecordArguments {
  std::vector<std::string> data;   // --data, repeatable
  driver::RecordSettings settings;  // --from, --to, --every, --step, --resample, --derivative, ...
};

// Adds --data, --from, --to, --every, --step, --resample, --derivative, --second-derivative,
// --edges, --integration, --precision, --weights, --split-at-gaps and --keep-outliers to `command`.
void add_record_options(CLI::App* command, RecordArguments& arguments);

// The records `--data` names, as the library takes them (none: the model's data statements).
std::vector<driver::RecordInput> record_inputs(const RecordArguments& arguments);

}  // namespace sidc
