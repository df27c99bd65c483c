// What every fit and selection shares, whichever face asks (the command line, the Python module):
// the settings that say how to evaluate the model on its records (the model's own `set` statements,
// overridden one by one), the form requested over the model's, and the records themselves, read
// from CSV or handed over in memory, bound as the model's first data statement binds them.
//
// Relies on: ir/settings.hpp (the settings), runtime/solve/options_from_settings.hpp (the one
// translation of settings into runtime options), runtime/records/ (reading and binding).
// Guarantees: every problem comes back as the Diagnostic the command line prints, never an
// exception; a record given in memory is moved, never copied.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "ir/compiled_model.hpp"
#include "ir/settings.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/records/clipping.hpp"
#include "runtime/records/isolated_outliers.hpp"
#include "runtime/records/records.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc::driver {

// The overrides of the model's evaluation settings, named as `sidc fit` names its options
// (`--second-derivative` is `second_derivative`); empty or unset: the model's own.
struct RecordSettings {
  std::optional<double> from, to, step, resample;
  std::optional<int> every;
  std::string derivative, second_derivative, edges, integration, precision, weights;
  // Isolated outliers of the outputs kept as recorded (runtime/records/isolated_outliers.hpp);
  // false: found, replaced by their neighbours' value and reported (`--keep-outliers`).
  bool keep_outliers = false;
  std::string keep_outliers_name = "--keep-outliers";  // how the face names that option in reports
  // A record with gaps (missing samples, faulty cells in the columns read) cut into its unbroken
  // stretches, each fitted as a record of its own (runtime/records/bind_record.hpp, unbroken_stretches).
  bool split_at_gaps = false;
  // The processes that read each record together, each its own byte range (CsvOptions::share; the
  // command line under mpirun; not owned). Null: every record read whole here.
  PartShare* share = nullptr;
};

// The model's settings overridden; a moving arc that cannot be read is the error.
std::variant<EvaluationSettings, Diagnostic> evaluation_settings(const ir::Model& model, const RecordSettings& settings);
// The same, translated into the fit's options, with the arithmetic (`precision`) and checked.
std::variant<FitOptions, Diagnostic> fit_options(const ir::Model& model, const RecordSettings& settings);

// The rewrite `--integrate N|auto` or `--form NAME` asks for (docs/language.md: `set integrate`,
// `set form`): nullopt when both are empty; an error when `integrate` is not 0-8 or `auto`.
std::variant<std::optional<ir::IntegrationRequest>, Diagnostic> integration_request(const std::string& integrate, const std::string& form);

// One record: a CSV path (read as `--data` reads it) or a record already in memory.
using RecordInput = std::variant<std::string, Record>;

struct LoadedRecords {
  std::vector<ir::DataSource> sources;  // paths resolved
  std::vector<SampledRecord> records;
  BindOptions bind;                     // as used, for further records (`--validate`)
  std::vector<OutlierScan> outliers;    // every output's isolated outliers replaced, by record (none kept)
  std::string notes;                    // what was done to the records before binding (split at gaps), for the report
  std::vector<Clipping> clipped;        // outputs that look clipped (a sensor at the end of its range), by record
};

// Stretches of a record split at its gaps shorter than this are left out (and listed).
inline constexpr std::size_t kMinStretchRows = 20;

// The records `inputs` name, each bound as the model's first data statement; with none, the
// model's own data statements, relative paths taken from `directory` (the model file's folder).
// `progress` (optional) hears how far each large CSV's reading is: "reading PATH (bytes)", done, total.
std::variant<LoadedRecords, Diagnostic> load_records(
    const CompiledModel& compiled, const std::string& directory, std::vector<RecordInput> inputs, const RecordSettings& settings,
    const std::function<void(const std::string& phase, std::size_t done, std::size_t total)>& progress = nullptr);

// One more record, bound like the others as the model's first data statement (read by `share`'s
// processes together when given, as load_records reads with RecordSettings::share), its outputs'
// isolated outliers replaced and added to `outliers` unless that is null.
std::variant<SampledRecord, Diagnostic> load_record(const ir::Model& model, RecordInput input, const BindOptions& bind,
                                                    PartShare* share = nullptr, std::vector<OutlierScan>* outliers = nullptr);

}  // namespace sidc::driver
