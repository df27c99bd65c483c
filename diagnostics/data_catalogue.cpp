#include "diagnostics/data_catalogue.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fmt/format.h>

#include "diagnostics/model_catalogue.hpp"

namespace sidc::data_diag {
namespace {

Diagnostic located(std::string code, std::string_view path, int row, int column, std::string message,
                   std::string hint = {}) {
  Diagnostic d;
  d.code = std::move(code);
  d.data_file = std::string(path);
  d.row = row;
  d.column = column;
  d.message = std::move(message);
  d.hint = std::move(hint);
  return d;
}

// Text as it may be shown on a terminal: printable ASCII only, and at most `limit` characters,
// so that binary bytes or a 10 MB field cannot garble the message. Cells and names are cut at
// 24 characters; paths are not cut.
std::string shown(std::string_view text, std::size_t limit = 24) {
  std::string out;
  for (char c : text.substr(0, limit)) {
    const auto u = static_cast<unsigned char>(c);
    out += (u >= 0x20 && u < 0x7f) ? c : '?';
  }
  if (text.size() > limit) out += "...";
  return out;
}

std::string shown_path(std::string_view path) { return shown(path, std::string_view::npos); }

const char* separator_hint(bool blank_separated) {
  return blank_separated
             ? "in a blank-separated file a run of spaces and tabs is one separator, so an empty cell cannot be "
               "written and a name must not contain a space; use commas, or fill the cell"
             : "every row needs one cell per header name; check for a stray or missing separator";
}

}  // namespace

Diagnostic cannot_open(std::string_view path, std::string_view reason) {
  Diagnostic d;
  d.code = "data-cannot-open";
  d.message = fmt::format("cannot read data file `{}`: {}", shown_path(path), reason);
  d.hint = "check the path: a path in a model's `data` statement is relative to the model file, one given with `--data` to the current directory";
  return d;
}

Diagnostic is_directory(std::string_view path) {
  Diagnostic d;
  d.code = "data-is-directory";
  d.message = fmt::format("data file `{}` is a directory", shown_path(path));
  d.hint = "name a CSV file inside it";
  return d;
}

Diagnostic not_a_regular_file(std::string_view path, std::string_view what) {
  Diagnostic d;
  d.code = "data-not-a-regular-file";
  d.message = fmt::format("data file `{}` is {}, not a regular file", shown_path(path), what);
  d.hint = "sidc reads a record whole, sized from the file: save it to a file first (`cat SOURCE > record.csv`)";
  return d;
}

Diagnostic changed_while_read(std::string_view path, std::string_view how) {
  Diagnostic d;
  d.code = "data-changed-while-read";
  d.message = fmt::format("data file `{}` {}", shown_path(path), how);
  d.hint = "another program is writing or truncating it: copy the record once it is complete, and fit the copy";
  return d;
}

Diagnostic empty_file(std::string_view path) {
  return located("data-empty-file", path, 1, 1, "data file holds no data (it is empty, or only comments and blank lines)",
                 "a record needs a header line of column names and one row per sample");
}

Diagnostic binary_file(std::string_view path, int row, int column) {
  return located("data-binary-file", path, row, column, "data file is not text (it contains a NUL byte)",
                 "sidc reads CSV text; export the record as CSV (UTF-16 text must be saved as UTF-8 or ASCII)");
}

Diagnostic no_data_rows(std::string_view path, int header_row) {
  return located("data-no-rows", path, header_row, 1, "data file has a header but no data rows",
                 "add one row of numbers per sample below the header");
}

Diagnostic invalid_csv_options(std::string_view why) {
  Diagnostic d;
  d.code = "data-invalid-options";
  d.message = fmt::format("invalid CSV options: {}", why);
  return d;
}

Diagnostic unterminated_quote(std::string_view path, int row, int column) {
  return located("data-unterminated-quote", path, row, column, "unterminated quote in the header",
                 "close the quoted name with `\"` before the end of the line");
}

Diagnostic duplicate_column(std::string_view path, int row, int column, std::string_view name, int first_column) {
  return located("data-duplicate-column", path, row, column,
                 fmt::format("duplicate column name `{}` (first used in column {})", shown(name), first_column),
                 "give every column a different name");
}

Diagnostic too_many_fields(std::string_view path, int row, int column, std::size_t expected, bool blank_separated) {
  return located("data-too-many-fields", path, row, column,
                 fmt::format("row has more fields than the {} column{} of the header", expected,
                             expected == 1 ? "" : "s"),
                 separator_hint(blank_separated));
}

Diagnostic too_few_fields(std::string_view path, int row, int column, std::size_t found, std::size_t expected,
                          bool blank_separated) {
  return located("data-too-few-fields", path, row, column,
                 fmt::format("row has {} field{} but the header has {} column{}", found, found == 1 ? "" : "s",
                             expected, expected == 1 ? "" : "s"),
                 separator_hint(blank_separated));
}

Diagnostic bad_cell(std::string_view path, int row, int column, std::string_view column_name, CellFault fault,
                    std::string_view text) {
  const std::string name = shown(column_name);
  const std::string quoted = text.empty() ? std::string() : fmt::format(" `{}`", shown(text));
  switch (fault) {
    case CellFault::empty:
      return located("data-empty-cell", path, row, column, fmt::format("empty cell in column `{}`", name),
                     "every sample of a column the model uses must hold a number; fill the cell, choose a time "
                     "window that leaves this row out, or give --split-at-gaps to fit the stretches either side as separate records");
    case CellFault::not_a_number:
      return located("data-nan-cell", path, row, column, fmt::format("cell{} in column `{}` is NaN", quoted, name),
                     "sidc needs a finite number in every used sample; fill the gap, choose a time window that "
                     "leaves this row out, or give --split-at-gaps to fit the stretches either side as separate records");
    case CellFault::infinite:
      return located("data-infinite-cell", path, row, column,
                     fmt::format("cell{} in column `{}` is infinite", quoted, name),
                     "sidc needs a finite number in every used sample; fix the cell or choose a time window that "
                     "leaves this row out");
    case CellFault::decimal_comma:
      return located("data-decimal-comma", path, row, column,
                     fmt::format("cell{} in column `{}` uses a decimal comma", quoted, name),
                     "write decimal points (1.5, not 1,5), or read the file with the decimal-comma option");
    case CellFault::out_of_range:
      return located("data-out-of-range-cell", path, row, column,
                     fmt::format("cell{} in column `{}` is beyond the range of a double", quoted, name),
                     "rescale the column; doubles reach about 1.8e308");
    case CellFault::non_numeric:
    case CellFault::none:
      break;
  }
  return located("data-non-numeric-cell", path, row, column,
                 fmt::format("cell{} in column `{}` is not a number", quoted, name),
                 "numbers look like 12, -0.5, .25, 760. or 1.5E+03; remove units and thousands separators");
}

Diagnostic unknown_column(std::string_view path, int header_row, std::string_view name,
                          const std::vector<std::string>& names) {
  // Any one-letter name is one edit away from any other, so for those only a difference of case
  // is a plausible slip (`X` for `x`); longer names take the catalogue's edit-distance rule.
  std::string near;
  if (name.size() == 1) {
    for (const auto& candidate : names)
      if (candidate.size() == 1 && std::tolower(static_cast<unsigned char>(candidate[0])) ==
                                       std::tolower(static_cast<unsigned char>(name[0])))
        near = candidate;
  } else {
    near = diag::nearest(name, names);
  }
  std::string list;
  for (std::size_t i = 0; i < names.size() && i < 12; ++i) list += (i ? ", " : "") + shown(names[i]);
  if (names.size() > 12) list += ", ...";
  return located("data-unknown-column", path, header_row > 0 ? header_row : 1, 1,
                 fmt::format("no column named `{}` (columns: {})", shown(name), list),
                 near.empty() ? std::string("name the column in the header line, or map the signal to a column")
                              : fmt::format("did you mean `{}`?", near));
}

Diagnostic too_few_samples(std::string_view path, int row, int column, std::string_view name, std::size_t count) {
  return located("data-too-few-samples", path, row, column,
                 fmt::format("time column `{}` has {} sample{}; a step needs at least 2", shown(name), count,
                             count == 1 ? "" : "s"));
}

Diagnostic time_repeats(std::string_view path, int row, int column, std::string_view name, double value) {
  return located("data-time-repeats", path, row, column,
                 fmt::format("time `{}` repeats the previous row's value {}", shown(name), value),
                 "remove the duplicated row");
}

Diagnostic time_goes_backwards(std::string_view path, int row, int column, std::string_view name, double previous,
                               double value) {
  return located("data-time-backwards", path, row, column,
                 fmt::format("time `{}` goes backwards, from {} to {}", shown(name), previous, value),
                 "rows must be in time order; sort the file or remove the misplaced row");
}

Diagnostic time_step_not_uniform(std::string_view path, int row, int column, std::string_view name, double found,
                                 double expected, double relative_tolerance) {
  return located("data-time-step-not-uniform", path, row, column,
                 fmt::format("time step of `{}` is {} here but {} elsewhere (tolerance {} relative)", shown(name),
                             found, expected, relative_tolerance),
                 "derivatives and integrals need uniform sampling; --split-at-gaps fits the stretches between gaps as "
                 "separate records, --resample interpolates onto a uniform grid; or fix the missing or extra samples");
}

Diagnostic invalid_resampling_step(double step) {
  Diagnostic d;
  d.code = "data-invalid-resampling-step";
  d.message = fmt::format("resampling step {} is not a positive number", step);
  d.hint = "give the step in the time column's units, such as --resample 0.01";
  return d;
}

Diagnostic too_many_resampled_rows(std::string_view path, double step, double asked, std::size_t rows, std::size_t limit, double mean_step) {
  Diagnostic d;
  d.code = "data-too-many-resampled-rows";
  d.message = fmt::format("resampling `{}` ({} rows) with step {} would make {:.3g} rows; at most {} are allowed (16 times the record's "
                          "rows, or 1000000 if that is more)",
                          shown_path(path), rows, step, asked, limit);
  d.hint = fmt::format("choose a step near the record's own: its mean step is {}", mean_step);
  return d;
}

Diagnostic empty_time_window(std::string_view path, std::string_view name, double from, double to, double first,
                             double last) {
  return located("data-empty-window", path, 1, 1,
                 fmt::format("no sample of `{}` lies in the window [{}, {}]; the record spans [{}, {}]", shown(name),
                             from, to, first, last),
                 "choose a window inside the record");
}

Diagnostic no_stretch_to_fit(std::string_view path) {
  Diagnostic d;
  d.code = "data-no-stretch";
  d.message = fmt::format("`{}` has no two neighbouring rows whose every used column holds a number: no stretch of it can be fitted",
                          shown_path(path));
  d.hint = "check the columns the model reads (its data statement binds them)";
  return d;
}

Diagnostic no_long_stretch(std::string_view path, std::size_t min_rows, std::size_t shorter) {
  Diagnostic d;
  d.code = "data-no-stretch";
  d.message = fmt::format("`{}` has no unbroken stretch of {} rows or more between its gaps ({} shorter)", shown_path(path), min_rows, shorter);
  d.hint = "fill the gaps, or --resample to interpolate across them";
  return d;
}

Diagnostic no_time_column(std::string_view path, int header_row) {
  return located("data-no-time-column", path, header_row, 1,
                 "the record has no time column (`t` or `time`) and no sampling step was given",
                 fmt::format("bind one in the model (`data \"{}\" (t = \"seconds\")`), or give the step with `set step = 0.01` "
                             "or `--step 0.01`", path));
}

Diagnostic empty_fit_window(std::string_view path, std::size_t samples, int order, std::size_t margin, bool cut_by_window) {
  Diagnostic d;
  d.code = "data-empty-fit-window";
  d.message = fmt::format("no samples of `{}` are left in the fit window", path);
  d.hint = order == 0 ? fmt::format("the record has {} samples{}", samples, cut_by_window ? "; `from`/`to` leave none of them" : "")
                      : fmt::format("the record has {} samples; derivatives of order {} lose {} at each edge{}", samples, order, margin,
                                    cut_by_window ? ", and `from`/`to` cut it further" : "");
  return d;
}

Diagnostic invalid_signal_options(std::string_view operation, std::string_view why) {
  Diagnostic d;
  d.code = "signal-invalid-options";
  d.message = fmt::format("invalid options for {}: {}", operation, why);
  return d;
}

Diagnostic signal_shorter_than_window(std::size_t samples, int window) {
  Diagnostic d;
  d.code = "signal-too-short";
  d.message = fmt::format("the signal has {} sample{} but the moving arc needs {}", samples, samples == 1 ? "" : "s",
                          window);
  d.hint = "use a longer record or a smaller window";
  return d;
}

Diagnostic too_short_for_any_arc(std::string_view path, std::string_view signal, int order, std::size_t samples, int needed) {
  Diagnostic d;
  d.code = "data-too-short-for-arc";
  d.message = fmt::format("`{}` in `{}` has {} sample{}, too few for any moving arc of its derivative {} (savgol(auto) needs at least {})",
                          signal, path, samples, samples == 1 ? "" : "s", order, needed);
  d.hint = "record more samples, or write the derivative operator yourself with `set derivative = savgol(window, order)`";
  return d;
}

Diagnostic constant_signal(std::string_view path, std::string_view signal) {
  Diagnostic d;
  d.severity = Severity::warning;
  d.code = "data-constant-signal";
  d.message = fmt::format("`{}` is constant in `{}`: its noise level is 0 and its derivatives are 0; savgol(auto) uses the smallest arc", signal, path);
  d.hint = "check the column: a constant signal carries no information about the dynamics";
  return d;
}

Diagnostic noise_exceeds_variation(std::string_view path, std::string_view signal, double sigma, double spread) {
  Diagnostic d;
  d.severity = Severity::warning;
  d.code = "data-noise-exceeds-variation";
  d.message = fmt::format("the noise of `{}` in `{}` (estimated sigma {:.4g}) exceeds its variation (standard deviation {:.4g}, "
                          "{:.4g} of it beyond the noise): its derivatives are mostly noise and the fit will not be reliable",
                          signal, path, sigma, spread, std::sqrt(std::max(0.0, spread * spread - sigma * sigma)));
  d.hint = "record the signal with less noise, or over a longer time, or average several records";
  return d;
}

}  // namespace sidc::data_diag

// ---- evaluation on data, pointing at the model term that asked for it --------------------------
namespace sidc::diag {

Diagnostic operation_not_finite(const Span& where, std::string_view operation, std::string_view owner, double time, std::string_view record) {
  return error("operation-not-finite", where,
               fmt::format("`{}`{} is not a finite number at t = {} in `{}`", operation, owner.empty() ? "" : fmt::format(" ({})", owner), time, record),
               "check the record there (a zero under a division or a log, a huge power), or narrow the fit window with `set from`/`set to`");
}

Diagnostic held_input_integral_unsupported(const Span& where, std::string_view term, std::string_view input) {
  return error("held-input-integral-unsupported", where,
               fmt::format("cannot integrate `{}` exactly: it multiplies an integral of the held input `{}` by something that varies "
                           "within a sample interval",
                           term, input),
               "sidc integrates a held input's pieces exactly, and integrals of them times a constant; write the model in weak form "
               "(`set form = weak`), which needs no nested integral, or declare the input `smooth`");
}

Diagnostic initial_value_unavailable(const Span& where, std::string_view value, double time, std::string_view record) {
  return error("initial-value-unavailable", where, fmt::format("`{}` has no value at t = {} in `{}`", value, time, record),
               "a derivative has no estimate near the edges of the record under `edges = drop`; use a later time or `set edges = shorten`");
}

Diagnostic initial_value_outside_record(const Span& where, std::string_view value, double time, double first, double last) {
  return error("initial-value-outside-record", where, fmt::format("`{}` asks for t = {}, outside the record ({} to {})", value, time, first, last),
               "give a time within the record");
}

Diagnostic signal_not_in_record(const Span& where, std::string_view signal, std::string_view record) {
  return error("signal-not-in-record", where, fmt::format("signal `{}` has no values in `{}`", signal, record),
               fmt::format("bind it to a column in the data statement, e.g. `data \"{}\" ({} = \"column\")`", record, signal));
}

Diagnostic no_data_file(const Span& where) {
  return error("no-data-file", where, "the model names no record to fit",
               "add `data \"record.csv\"` to the model, or give one with `sidc fit --data record.csv`");
}

Diagnostic window_too_short(std::string_view record, std::size_t rows, std::size_t parameters, int margin) {
  return error("window-too-short", {},
               fmt::format("`{}` leaves {} rows in the fit window for {} parameters", record, rows, parameters),
               fmt::format("the moving-arc derivatives lose {} samples at each edge; use a longer record, a wider window "
                           "(`set from`/`set to`), fewer parameters, or `set edges = shorten`", margin));
}

Diagnostic local_window_too_long(std::string_view record, double width, double samples, std::size_t available, double span) {
  return error("local-window-too-long", {},
               fmt::format("the local window of {:g} ({:g} samples) is longer than `{}` can give ({} samples)", width, samples,
                           record, available),
               fmt::format("give a window of at most {:g}, or leave out the local fits (`--local`, `set local`)", span));
}

Diagnostic local_window_too_short(std::string_view record, double width, std::size_t samples, std::size_t rows,
                                  std::size_t parameters, double least_width) {
  return error("local-window-too-short", {},
               fmt::format("the local window of {:g} ({} sample{} of `{}`) holds at most {} row{} for {} parameters", width, samples,
                           samples == 1 ? "" : "s", record, rows, rows == 1 ? "" : "s", parameters),
               fmt::format("give a window of at least {:g} (many times that for estimates worth having), or fewer parameters", least_width));
}

Diagnostic weak_form_mixed(const Span& where) {
  return error("weak-form-mixed", where,
               "this equation shares parameters with an equation of the weak form but is not of the weak form itself",
               "write `set form = weak` before every equation that shares its parameters, or before none of them");
}

Diagnostic weak_form_too_short(std::string_view record, std::size_t samples, std::size_t needed, std::size_t rows) {
  return error("weak-form-too-short", {},
               fmt::format("the fit window of `{}` holds {} samples; the weak form needs at least {} for {} subdomains of its "
                           "narrowest test function",
                           record, samples, needed, rows),
               "use a longer record or a wider window (`set from`/`set to`), fewer parameters, or another form "
               "(`set form = derivative` or `integrated`)");
}

Diagnostic weight_not_valid(const Span& where, std::string_view weights, double value, double time, std::string_view record) {
  return error("weight-not-valid", where,
               fmt::format("the weights `{}` are {} at t = {} in `{}`; a weight must be a finite number >= 0 (eq. 2-1.6)", weights,
                           value, time, record),
               "write the weights so that they cannot go negative (e.g. a square or an abs()), or narrow the fit window with "
               "`set from`/`set to`");
}
// [end of compiler-owned section]

// ---- simulation (compiler/explicit_form_pass.cpp, runtime/simulate/simulate.cpp)

}  // namespace sidc::diag
