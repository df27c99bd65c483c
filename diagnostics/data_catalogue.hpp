// Every message sidc prints about a data file (a record), one named constructor each, the data
// counterpart of diagnostics/model_catalogue.hpp. runtime/records/ (csv_file.cpp, csv_parser.cpp,
// records.cpp) and sampling.cpp build Diagnostics only through these, so the wording lives in one
// place and the bad-record tests (tests/runtime/bad_records_test.cpp, files in tests/data/bad/) pin
// every one of them.
//
// Locations are `file:row:col` with row = 1-based line number in the file (comments, blank lines
// and the header count) and col = 1-based field index on that line. Codes are stable: tests rely
// on them. A problem with no sensible location (the file cannot be opened)
// carries no data_file and names the path in its message instead.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "diagnostics/diagnostic.hpp"

namespace sidc::data_diag {

// What is wrong with one cell of a numeric column.
enum class CellFault : unsigned char {
  none,
  empty,          // nothing between the separators
  not_a_number,   // the text `nan` (any case)
  infinite,       // `inf`, `-Infinity`, ...
  non_numeric,    // text that is not a number at all
  decimal_comma,  // `1,5` in a semicolon or blank separated file
  out_of_range,   // beyond the range of a double (1e400)
};

// ---- the file as a whole (csv_file.cpp, csv_parser.cpp) -----------------------------------------
Diagnostic cannot_open(std::string_view path, std::string_view reason);
Diagnostic is_directory(std::string_view path);
// A FIFO, a device or a socket named as a record; `what`: "a FIFO", "a character device", ...
Diagnostic not_a_regular_file(std::string_view path, std::string_view what);
// The record's length changed between its fstat and its read (a logger writing or rotating it).
Diagnostic changed_while_read(std::string_view path, std::string_view how);
Diagnostic empty_file(std::string_view path);
Diagnostic binary_file(std::string_view path, int row, int column);
Diagnostic no_data_rows(std::string_view path, int header_row);
Diagnostic invalid_csv_options(std::string_view why);

// ---- the header (csv_parser.cpp) ---------------------------------------------------------------
Diagnostic unterminated_quote(std::string_view path, int row, int column);
Diagnostic duplicate_column(std::string_view path, int row, int column, std::string_view name, int first_column);

// ---- row shape (csv_parser.cpp) ----------------------------------------------------------------
Diagnostic too_many_fields(std::string_view path, int row, int column, std::size_t expected, bool blank_separated);
Diagnostic too_few_fields(std::string_view path, int row, int column, std::size_t found, std::size_t expected,
                          bool blank_separated);

// ---- a used column (records.cpp) ---------------------------------------------------------------
// `text` is the cell as written (may be empty when it is not known); it is shown sanitised.
Diagnostic bad_cell(std::string_view path, int row, int column, std::string_view column_name, CellFault fault,
                    std::string_view text);
Diagnostic unknown_column(std::string_view path, int header_row, std::string_view name,
                          const std::vector<std::string>& names);

// ---- the time column (sampling.cpp) ------------------------------------------------------------
Diagnostic too_few_samples(std::string_view path, int row, int column, std::string_view name, std::size_t count);
Diagnostic time_repeats(std::string_view path, int row, int column, std::string_view name, double value);
Diagnostic time_goes_backwards(std::string_view path, int row, int column, std::string_view name, double previous,
                               double value);
Diagnostic time_step_not_uniform(std::string_view path, int row, int column, std::string_view name, double found,
                                 double expected, double relative_tolerance);
Diagnostic invalid_resampling_step(double step);
// A resampling step so small that the record would grow past its limit (runtime/records/sampling.hpp,
// max_resampled_rows): `asked` rows (a double: it may exceed any integer) of a record of `rows`.
Diagnostic too_many_resampled_rows(std::string_view path, double step, double asked, std::size_t rows, std::size_t limit, double mean_step);
Diagnostic empty_time_window(std::string_view path, std::string_view name, double from, double to, double first,
                             double last);

// ---- signal operations (savitzky_golay.cpp, simpson.cpp); no location: the caller adds the
// span of the model term that asked for the operation ---------------------------------------------
Diagnostic invalid_signal_options(std::string_view operation, std::string_view why);
// Binding a record to a model (runtime/records/bind_record.cpp, runtime/operators/evaluate.cpp).
Diagnostic no_time_column(std::string_view path, int header_row);
// --split-at-gaps on a record without two neighbouring good rows, or without a stretch of
// `min_rows` between its gaps (`shorter`: how many it has that are shorter).
Diagnostic no_stretch_to_fit(std::string_view path);
Diagnostic no_long_stretch(std::string_view path, std::size_t min_rows, std::size_t shorter);
Diagnostic empty_fit_window(std::string_view path, std::size_t samples, int order, std::size_t margin, bool cut_by_window);
Diagnostic signal_shorter_than_window(std::size_t samples, int window);

// ---- noise levels and savgol(auto) (runtime/operators/operator_choice.cpp) -----------------------
// Errors: the record has fewer samples than the smallest moving arc for that derivative.
Diagnostic too_short_for_any_arc(std::string_view path, std::string_view signal, int order, std::size_t samples, int needed);
// Warnings (severity warning), printed by `sidc fit` and kept in fit.json:
Diagnostic constant_signal(std::string_view path, std::string_view signal);
Diagnostic noise_exceeds_variation(std::string_view path, std::string_view signal, double sigma, double spread);

}  // namespace sidc::data_diag

namespace sidc::diag {

// ---- evaluation on data (runtime/), pointing at the model term that asked for it
Diagnostic operation_not_finite(const Span& where, std::string_view operation, std::string_view owner, double time, std::string_view record);
// A term that holds a held or linear input both directly and inside an integral, or an integral
// of one multiplied by a signal: runtime/operators/piecewise_inputs.hpp integrates neither exactly.
Diagnostic held_input_integral_unsupported(const Span& where, std::string_view term, std::string_view input);
Diagnostic initial_value_unavailable(const Span& where, std::string_view value, double time, std::string_view record);
Diagnostic initial_value_outside_record(const Span& where, std::string_view value, double time, double first, double last);
Diagnostic no_data_file(const Span& where);
Diagnostic signal_not_in_record(const Span& where, std::string_view signal, std::string_view record);
Diagnostic window_too_short(std::string_view record, std::size_t rows, std::size_t parameters, int margin);
// The weak form's narrowest subdomains do not fit `rows` times into the fit window of `record`.
// An equation of another form sharing parameters with a weak-form one (rows of samples and of
// subdomains cannot be stacked).
Diagnostic weak_form_mixed(const Span& where);
Diagnostic weak_form_too_short(std::string_view record, std::size_t samples, std::size_t needed, std::size_t rows);
// `set weights = <expression>` (eq. 2-1.6) is negative, NaN or infinite on a row of the fit window.
Diagnostic weight_not_valid(const Span& where, std::string_view weights, double value, double time, std::string_view record);
// A local fit's window (`sidc fit --local`, `set local`) longer than the record's fit window, or
// with fewer rows than the parameters it must determine.
Diagnostic local_window_too_long(std::string_view record, double width, double samples, std::size_t available, double span);
Diagnostic local_window_too_short(std::string_view record, double width, std::size_t samples, std::size_t rows,
                                  std::size_t parameters, double least_width);

}  // namespace sidc::diag
