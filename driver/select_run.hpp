// `sidc select`'s work without its command line, for every face that selects
// (cli/select_command.cpp, the Python module): the model in the weak form when it names none, the
// options checked against the model's parameters, the records, then the search (thesis section
// 2-3), with the integrated form as the fallback when the records are too short for the weak one.
//
// Two steps, as for the fit (fit_run.hpp): prepare_select, then run_select.
//
// Relies on: compiler/pipeline.hpp (the forms), runtime/select/select.hpp, runtime/simulate/
// validate.hpp (the simulation criterion). Guarantees: every problem is a Failure holding the
// Diagnostics the command line prints; nothing is written or printed except through FitOutput.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "driver/fit_run.hpp"
#include "runtime/select/select.hpp"

namespace sidc::driver {

// `sidc select`'s options beyond the records' (docs/cli.md), by their names there.
struct SelectSettings {
  RecordSettings records;
  std::string method = "automatic", rule = "elbow";  // checked by the face: one of the documented names
  std::vector<std::string> required, dropped;
  std::vector<std::pair<std::string, std::vector<std::string>>> groups;  // name, members
  int folds = 5, bootstrap = 0, max_size = -1;
  std::uint64_t seed = 1;
  bool simulate = false, keep_drift = false;
  std::size_t simulate_samples = 100000;
  bool keywords = false;  // messages name options as keywords (`keep_drift`) rather than `--keep-drift`
  // As FitSettings' (fit_run.hpp): the rows shared among processes, threads each, the report's line.
  RowShare* share = nullptr;
  int threads = 0;
  std::string processes;
  std::optional<std::size_t> stream_above;  // FitOptions::stream_above_entries (unset: the default)
};

struct SelectRun {
  CompiledModel compiled;  // `integrated` is the form searched
  std::string model_path;
  SelectSettings settings;
  SelectOptions options;
  LoadedRecords loaded;
  bool weak_by_default = false;  // the model names no form
  std::string form_note;         // the report's line saying which form was searched and why
  std::optional<SelectSummary> summary;
};

// `progress` (optional) hears how far a large record's reading is, as for the fit.
std::variant<std::unique_ptr<SelectRun>, Failure> prepare_select(
    CompiledModel compiled, std::string model_path, const std::string& directory, std::vector<RecordInput> inputs, SelectSettings settings,
    const std::function<void(const std::string& phase, std::size_t done, std::size_t total)>& progress = nullptr);

// The search; the drift absorbers as warnings and the report through `out`.
std::optional<Failure> run_select(SelectRun& run, const FitOutput& out);

}  // namespace sidc::driver
