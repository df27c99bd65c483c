// Every message sidc prints about its command line and the files it is told to read or write, one
// named constructor each, the command-line counterpart of model_catalogue.hpp and
// data_catalogue.hpp. cli/ builds its errors only through these, so the wording lives here.
// They carry no location: they are about options, not about text in a file. Codes are stable.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "diagnostics/diagnostic.hpp"

namespace sidc::cli_diag {

// ---- files named on the command line -----------------------------------------------------------
Diagnostic is_directory(std::string_view path);
Diagnostic cannot_read(std::string_view path, std::string_view reason);
// `sidc compile` with a model file it cannot read.
Diagnostic model_not_read(const Diagnostic& why);
// `why` as given by report/atomic_file.hpp ("cannot write `FILE`: REASON").
Diagnostic cannot_write(std::string_view why, std::string_view hint = {});
Diagnostic cannot_create_directory(std::string_view path, std::string_view reason, std::string_view hint = {});
// An output path that names one of the run's inputs (the model, a record, a compiled model).
Diagnostic output_is_input(std::string_view output, std::string_view input);
// A model or parameter file that is not a regular file (a FIFO, a device); `what`: "a FIFO", ...
Diagnostic not_a_regular_file(std::string_view path, std::string_view what);
// Writing to standard output failed (a full disk, a closed pipe).
Diagnostic cannot_write_stdout(std::string_view reason);
Diagnostic not_a_compiled_model(std::string_view path);
Diagnostic compiled_model_version(std::string_view path, int found, int expected);
Diagnostic invalid_compiled_model(std::string_view path, std::string_view what);
Diagnostic cannot_draw_figure(std::string_view figure, std::string_view why);
Diagnostic cannot_read_back_figure(std::string_view figure, std::string_view why);
Diagnostic no_compiled_model();
// `sidc fit` without a model, and several compiled models here: which one is not guessed.
Diagnostic several_compiled_models(const std::vector<std::string>& names);
Diagnostic compiled_model_not_json(std::string_view path);
Diagnostic model_changed_since_compiled(std::string_view model, std::string_view compiled);
Diagnostic not_a_fit_file(std::string_view path);

// An output named on the command line that cannot be written, found before any work is done.
Diagnostic output_not_writable(std::string_view option, std::string_view path, std::string_view reason);

// ---- the command line as a whole ---------------------------------------------------------------
// `sidc fitt`: `nearest` is the closest subcommand ("" when none is close), `names` all of them.
Diagnostic unknown_subcommand(std::string_view name, std::string_view nearest, std::string_view names);
// A usage error found by the option parser (CLI11): its sentence, and where to read the options.
Diagnostic usage(std::string_view what, std::string_view command);

// ---- options -----------------------------------------------------------------------------------
// An option's own check failed; `why` says how (from an options struct's is_valid()).
Diagnostic invalid_options(std::string_view why);
Diagnostic not_a_moving_arc(std::string_view text);
Diagnostic unknown_parameter(std::string_view option, std::string_view name, const std::vector<std::string>& names);
// `sidc simulate --param NAME=...` for a name the model lacks; `names`: its parameters, listed.
Diagnostic no_such_parameter(std::string_view name, std::string_view names);
Diagnostic not_name_value(std::string_view option, std::string_view text, std::string_view example);
Diagnostic value_not_finite(std::string_view option, std::string_view text, std::string_view value, std::string_view example);
Diagnostic missing_parameter_values(std::string_view names);
Diagnostic not_an_output(std::string_view text, std::string_view name);
Diagnostic initial_order_too_high(std::string_view text, std::string_view name, int order);

// ---- sidc fit ----------------------------------------------------------------------------------
// A record (.csv) where a model belongs: `sidc fit --data a.csv b.csv model.sid`.
Diagnostic record_as_model(std::string_view path);
Diagnostic cannot_validate(std::string_view record, const Diagnostic& why);
Diagnostic rank_deficient();
// `--stride` without `--local` or `--forget`; `--local` with `--forget` (sidc fit, issue 18).
Diagnostic stride_without_local_fit();
Diagnostic local_and_forget();
Diagnostic pictures_of_several_models(std::size_t models);
// A warning: the instrumental-variable iteration (`--estimator iv`) did not converge; `statement`
// says what happened and which estimate is kept (runtime/solve/instrumental_variables.hpp).
Diagnostic instrumental_variables_not_converged(std::string_view statement);
// The noise check found intervals too narrow, or estimates biased, under the record's noise.
Diagnostic noise_biases_estimates(std::string_view statement);

// ---- sidc export -------------------------------------------------------------------------------
// The fitted model cannot be written as code: `why` says what stands in the way.
Diagnostic cannot_export(std::string_view why);
// A fit.json from before fit.json carried the model's text.
Diagnostic fit_file_without_model(std::string_view path);

// ---- sidc select -------------------------------------------------------------------------------
Diagnostic required_and_dropped(std::string_view name);
Diagnostic bad_group(std::string_view spec);
Diagnostic empty_group_member(std::string_view spec);
Diagnostic in_two_groups(std::string_view name, std::string_view first, std::string_view second);
Diagnostic simulate_needs_one_group();
Diagnostic simulate_needs_explicit_form(const Diagnostic& why);
Diagnostic selection_failed(std::string_view message);

// ---- sidc simulate -----------------------------------------------------------------------------
Diagnostic end_not_after_start(double t1, double t0);
Diagnostic end_not_after_t0(double t1, double t0);
Diagnostic option_for_other_method(std::string_view option, std::string_view method, std::string_view hint);
Diagnostic step_with_record();
Diagnostic every_without_record();
Diagnostic too_few_samples_between(std::string_view record, double from, double to, double first, double last);
Diagnostic grid_needs_end_and_step();
// `count` as a double: it may be past any integer type (a step of 1e-300).
Diagnostic too_many_output_rows(double count, double step, double t0, double t1);
Diagnostic input_without_values(std::string_view input);
Diagnostic simulation_stopped(std::string_view message);

// ---- the Python module (python/): keyword settings and numpy records -----------------------------
// Its keyword arguments are the command line's options (`every=2` is `--every 2`), so they are
// reported like options; its records are dicts of 1-D arrays named like a CSV's columns.
// `function` is e.g. `fit`; `nearest` the closest keyword ("" when none is close), `names` all.
Diagnostic unknown_keyword(std::string_view function, std::string_view name, std::string_view nearest, std::string_view names);
Diagnostic keyword_not_one_of(std::string_view name, std::string_view value, std::string_view choices);
Diagnostic keyword_wrong_type(std::string_view name, std::string_view given, std::string_view expected);
// `record` names the record (`<arrays>`, `<arrays 2>`); columns by their key.
Diagnostic array_lengths_differ(std::string_view record, std::string_view column, std::size_t length, std::string_view first,
                                std::size_t first_length);
Diagnostic array_not_float(std::string_view record, std::string_view column, std::string_view dtype);
Diagnostic array_not_one_dimensional(std::string_view record, std::string_view column, std::size_t dimensions);
Diagnostic record_without_columns(std::string_view record);
Diagnostic not_a_record(std::string_view given);

}  // namespace sidc::cli_diag
