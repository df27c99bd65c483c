// What `sidc fit` and `sidc select` share: the options that say which records to read and how to
// evaluate the model on them, turned into FitOptions and bound SampledRecords the same way for both.
//
// Relies on: the model's settings (ir/settings.hpp), which the options override one by one, and
// runtime/solve/options_from_settings.hpp, the one translation of settings into runtime options.
// Guarantees: the records are the command line's `--data` files (bound as the model's first data
// statement), else the model's data statements, with relative paths taken from the compiled
// model's folder; every problem comes back as a message for stderr and an exit code, never an
// exception.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ir/compiled_model.hpp"
#include "ir/settings.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {

struct RecordArguments {
  std::vector<std::string> data;
  std::optional<double> from, to, step, resample;
  std::optional<int> every;
  std::string derivative, second_derivative, edges, integration, precision, weights;
};

// Adds --data, --from, --to, --every, --step, --resample, --derivative, --second-derivative,
// --edges, --integration, --precision and --weights to `command`.
void add_record_options(CLI::App* command, RecordArguments& arguments);

// The model's settings overridden by the command line; nullopt with `error` (a usage error).
std::optional<EvaluationSettings> evaluation_settings(const ir::Model& model, const RecordArguments& arguments, std::string& error);
// The same, translated (runtime/solve/options_from_settings.hpp), with --precision.
std::optional<FitOptions> fit_options(const ir::Model& model, const RecordArguments& arguments, std::string& error);

struct LoadedRecords {
  std::vector<ir::DataSource> sources;  // paths resolved
  std::vector<SampledRecord> records;
  BindOptions bind;                     // as used, for further records (`--validate`)
};

// Reads and binds the records; nullopt with `error` (rendered diagnostics, a user error).
std::optional<LoadedRecords> load_records(const CompiledModel& compiled, const std::string& compiled_path,
                                          const RecordArguments& arguments, std::string& error);

// One more record, bound like the others as the model's first data statement.
std::optional<SampledRecord> load_record(const ir::Model& model, const std::string& path, const BindOptions& bind, std::string& error);

}  // namespace sidc
