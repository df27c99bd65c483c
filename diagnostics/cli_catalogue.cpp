#include "diagnostics/cli_catalogue.hpp"

#include <cctype>
#include <fmt/format.h>

#include "diagnostics/model_catalogue.hpp"

namespace sidc::cli_diag {
namespace {

Diagnostic message(std::string code, std::string text, std::string hint = {}, Severity severity = Severity::error) {
  Diagnostic d = diag::error(std::move(code), Span{}, std::move(text), std::move(hint));
  d.severity = severity;
  return d;
}

}  // namespace

Diagnostic is_directory(std::string_view path) { return message("is-directory", fmt::format("`{}` is a directory, not a file", path)); }

Diagnostic cannot_read(std::string_view path, std::string_view reason) {
  return message("cannot-read", fmt::format("cannot read `{}`: {}", path, reason));
}

Diagnostic model_not_read(const Diagnostic& why) {
  Diagnostic d = why;
  d.hint = "give the path of a model file, e.g. `sidc compile examples/thesis-4-1/quasi_linear.sid`";
  return d;
}

Diagnostic cannot_write(std::string_view why, std::string_view hint) { return message("cannot-write", std::string(why), std::string(hint)); }

Diagnostic cannot_create_directory(std::string_view path, std::string_view reason, std::string_view hint) {
  return message("cannot-create-directory", fmt::format("cannot create `{}`: {}", path, reason), std::string(hint));
}

Diagnostic output_is_input(std::string_view output, std::string_view input) {
  return message("output-is-input", fmt::format("output `{}` is `{}`, an input of this run: writing it would destroy it", output, input),
                 "choose another output path");
}

Diagnostic not_a_regular_file(std::string_view path, std::string_view what) {
  return message("not-a-regular-file", fmt::format("cannot read `{}`: it is {}, not a regular file", path, what),
                 "sidc reads model and parameter files whole; save the text to a file first");
}

Diagnostic cannot_write_stdout(std::string_view reason) {
  return message("cannot-write-stdout", fmt::format("cannot write standard output: {}", reason),
                 "the output is incomplete; free space on the disk it goes to, or read it whole (not through `head`)");
}

Diagnostic not_a_compiled_model(std::string_view path) { return message("not-a-compiled-model", fmt::format("`{}` is not a compiled sidc model", path)); }

Diagnostic compiled_model_version(std::string_view path, int found, int expected) {
  return message("compiled-model-version", fmt::format("`{}` was written in compiled-model format {}, this sidc reads format {}", path, found, expected));
}

Diagnostic invalid_compiled_model(std::string_view path, std::string_view what) {
  return message("invalid-compiled-model", fmt::format("`{}` is not a valid compiled model ({}); compile the model again with `sidc compile`", path, what));
}

Diagnostic cannot_draw_figure(std::string_view figure, std::string_view why) {
  return message("cannot-draw-figure", fmt::format("cannot draw figure `{}`: {}", figure, why));
}

Diagnostic cannot_read_back_figure(std::string_view figure, std::string_view why) {
  return message("cannot-read-back-figure", fmt::format("cannot read back figure `{}`: {}", figure, why));
}

Diagnostic no_compiled_model() {
  return message("no-compiled-model", "no compiled model (*.sidc.json) in this directory",
                 "run `sidc compile model.sid` first, or name one: `sidc fit model.sidc.json`");
}

Diagnostic several_compiled_models(const std::vector<std::string>& names) {
  std::string list;
  for (const auto& n : names) list += fmt::format("{}`{}`", list.empty() ? "" : ", ", n);
  return message("several-compiled-models", fmt::format("{} compiled models in this directory ({}), and none named", names.size(), list),
                 fmt::format("name the one to fit: `sidc fit {}`", names.front()));
}

Diagnostic output_not_writable(std::string_view option, std::string_view path, std::string_view reason) {
  return message("output-not-writable", fmt::format("`{} {}` cannot be written: {}", option, path, reason),
                 "choose a writable place; nothing was done, so nothing is lost");
}

Diagnostic unknown_subcommand(std::string_view name, std::string_view nearest, std::string_view names) {
  return message("unknown-subcommand", fmt::format("unknown subcommand `{}`", name),
                 nearest.empty() ? fmt::format("the subcommands are: {} (`sidc --help` says what each does)", names)
                                 : fmt::format("did you mean `{}`? (the subcommands are: {})", nearest, names));
}

Diagnostic usage(std::string_view what, std::string_view command) {
  std::string text(what);
  if (!text.empty()) text[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(text[0])));
  return message("usage", text, fmt::format("`{} --help` lists the {}", command, command == "sidc" ? "subcommands" : "options"));
}

Diagnostic compiled_model_not_json(std::string_view path) {
  return message("compiled-model-not-json", fmt::format("`{}` is not JSON; compile the model again with `sidc compile`", path));
}

Diagnostic model_changed_since_compiled(std::string_view model, std::string_view compiled) {
  return message("model-changed", fmt::format("`{}` changed since `{}` was compiled", model, compiled), fmt::format("run `sidc compile {}` again", model),
                 Severity::warning);
}

Diagnostic not_a_fit_file(std::string_view path) {
  return message("not-a-fit-file", fmt::format("`{}` is not a fit.json written by `sidc fit --out`", path),
                 "run `sidc fit MODEL --out DIR` and pass DIR/fit.json");
}

Diagnostic invalid_options(std::string_view why) { return message("invalid-options", std::string(why)); }

Diagnostic not_a_moving_arc(std::string_view text) {
  return message("not-a-moving-arc", fmt::format("`--derivative {}` is not a moving-arc operator", text), "write e.g. `--derivative \"savgol(7, 3)\"`");
}

Diagnostic unknown_parameter(std::string_view option, std::string_view name, const std::vector<std::string>& names) {
  const std::string near = diag::nearest(name, names);
  std::string all;
  for (const auto& n : names) all += (all.empty() ? "" : ", ") + n;
  return message("unknown-parameter", fmt::format("{} `{}`: the model has no parameter `{}`", option, name, name),
                 near.empty() ? "the parameters are " + all : fmt::format("did you mean `{}`?", near));
}

Diagnostic no_such_parameter(std::string_view name, std::string_view names) {
  return message("no-such-parameter", fmt::format("`--param {}=...`: the model has no parameter `{}`", name, name), fmt::format("its parameters are {}", names));
}

Diagnostic not_name_value(std::string_view option, std::string_view text, std::string_view example) {
  return message("not-name-value", fmt::format("`{} {}` is not NAME=VALUE", option, text), fmt::format("write e.g. `{} {}`", option, example));
}

Diagnostic value_not_finite(std::string_view option, std::string_view text, std::string_view value, std::string_view example) {
  return message("value-not-finite", fmt::format("`{} {}`: `{}` is not a finite number", option, text, value), fmt::format("write e.g. `{} {}`", option, example));
}

Diagnostic missing_parameter_values(std::string_view names) {
  return message("missing-parameter-values", fmt::format("no value for {}", names),
                 "give every parameter a value with `--param NAME=VALUE`, or pass a fit's `--params fit.json`");
}

Diagnostic not_an_output(std::string_view text, std::string_view name) {
  return message("not-an-output", fmt::format("`--initial {}`: `{}` is not an output of the model", text, name),
                 "initial conditions are for outputs and their derivatives below the highest");
}

Diagnostic initial_order_too_high(std::string_view text, std::string_view name, int order) {
  return message("initial-order-too-high",
                 fmt::format("`--initial {}`: the state of `{}` is its derivatives of order 0 to {}; the equation gives order {}", text, name, order - 1, order),
                 "drop this initial condition");
}

Diagnostic record_as_model(std::string_view path) {
  return message("record-as-model", fmt::format("`{}` is a record, but it stands where `sidc fit` expects a model", path),
                 "`--data` takes one file: give each record its own, `--data a.csv --data b.csv`, then the model");
}

Diagnostic cannot_validate(std::string_view record, const Diagnostic& why) {
  return message("cannot-validate", fmt::format("cannot validate against `{}`: {}", record, render(why)));
}

Diagnostic rank_deficient() {
  return message("rank-deficient", "the least-squares problem is rank deficient: some operations are (nearly) dependent (see the report)",
                 "drop one operation of each dependent group, or give the record more excitation");
}

Diagnostic instrumental_variables_not_converged(std::string_view statement) {
  return message("iv-not-converged", fmt::format("instrumental variables: {}", statement),
                 "the report's `Instrumental variables` section says which estimate it kept; the equation-error fit above is "
                 "unchanged",
                 Severity::warning);
}

Diagnostic noise_biases_estimates(std::string_view statement) {
  return message("noise-biases-estimates", fmt::format("noise check: {}", statement),
                 "the report's `noise check` section gives each parameter's scatter and shift; `sidc fit --refine` fits by "
                 "the simulation error, whose intervals hold under noise",
                 Severity::warning);
}

Diagnostic pictures_of_several_models(std::size_t models) {
  return message("pictures-of-several-models", fmt::format("--plots and --report draw one model's fit, and {} models were given", models),
                 "fit the models together for the comparison table, and each alone with --plots or --report");
}

Diagnostic cannot_export(std::string_view why) {
  return message("cannot-export", fmt::format("cannot export the fitted model: {}", why),
                 "`--as latex` writes any model; C and Python need equations that code alone can evaluate");
}

Diagnostic fit_file_without_model(std::string_view path) {
  return message("fit-file-without-model", fmt::format("`{}` does not hold the model's text (it was written by an older sidc)", path),
                 "fit the model again with `sidc fit MODEL --out DIR` and export DIR/fit.json");
}

Diagnostic required_and_dropped(std::string_view name) {
  return message("required-and-dropped", fmt::format("`{}` is both required (--require) and dropped (--drop)", name));
}

Diagnostic bad_group(std::string_view spec) {
  return message("bad-group", fmt::format("`--group {}` is not of the form NAME=p1,p2,...", spec), "e.g. `--group damper=c1[1],c1[2],c1[3]`");
}

Diagnostic empty_group_member(std::string_view spec) {
  return message("empty-group-member", fmt::format("`--group {}` has an empty parameter name", spec));
}

Diagnostic in_two_groups(std::string_view name, std::string_view first, std::string_view second) {
  return message("in-two-groups", fmt::format("`{}` is in two groups, `{}` and `{}`", name, first, second));
}

Diagnostic simulate_needs_one_group() {
  return message("simulate-needs-one-group", "--simulate ranks the subsets of one equation group, and this model has several",
                 "select each group's operations from a model of that group alone");
}

Diagnostic simulate_needs_explicit_form(const Diagnostic& why) {
  Diagnostic d = why;
  d.hint = d.hint.empty() ? "--simulate needs equations that can be solved for their highest derivatives"
                          : d.hint + "\nhint: --simulate needs equations that can be solved for their highest derivatives";
  return d;
}

Diagnostic selection_failed(std::string_view text) { return message("selection-failed", std::string(text)); }

Diagnostic end_not_after_start(double t1, double t0) {
  return message("end-not-after-start", fmt::format("`--t1 {}` is not after `--t0 {}`", t1, t0));
}

Diagnostic end_not_after_t0(double t1, double t0) { return message("end-not-after-t0", fmt::format("`--t1 {}` is not after t0 = {}", t1, t0)); }

Diagnostic option_for_other_method(std::string_view option, std::string_view method, std::string_view hint) {
  return message("option-for-other-method", fmt::format("`{}` is for `--method {}`", option, method), std::string(hint));
}

Diagnostic stride_without_local_fit() {
  return message("stride-without-local-fit", "`--stride` spaces the local fits, but none was asked for",
                 "add `--local WIDTH` (windows along the record) or `--forget LAMBDA` (recursive estimates), or drop `--stride`");
}

Diagnostic local_and_forget() {
  return message("local-and-forget", "`--local` (windows of a fixed width) and `--forget` (exponential forgetting) are two ways of the same thing",
                 "give one of them");
}

Diagnostic step_with_record() {
  return message("step-with-record",
                 "`--step` makes a time grid for a run without a record, but the simulation has one (`--data` or the model's data statement)",
                 "use `--every K` to thin the record");
}

Diagnostic every_without_record() {
  return message("every-without-record", "`--every` thins a record, but the simulation has none", "give one with `--data record.csv`");
}

Diagnostic too_few_samples_between(std::string_view record, double from, double to, double first, double last) {
  return message("too-few-samples-between", fmt::format("`{}` has fewer than two samples between t = {} and t = {}", record, from, to),
                 fmt::format("the record runs from {} to {}", first, last));
}

Diagnostic grid_needs_end_and_step() {
  return message("grid-needs-end-and-step", "without a record, the time grid needs `--t1` and `--step` (and `--t0`, default 0)",
                 "e.g. `--t1 1 --step 0.01`, or give a record with `--data`");
}

Diagnostic too_many_output_rows(double count, double step, double t0, double t1) {
  // Whole counts as integers; those past 2^53 (a step of 1e-300) with an exponent.
  const std::string steps = count < 9e15 ? fmt::format("{}", static_cast<long long>(count)) : fmt::format("{:.3g}", count);
  return message("too-many-output-rows", fmt::format("{} steps of {} from {} to {} is more than 10^7 output rows", steps, step, t0, t1),
                 "use a larger `--step`");
}

Diagnostic input_without_values(std::string_view input) {
  return message("input-without-values",
                 fmt::format("input `{}` has no values: the simulation has no record and the model gives no definition", input),
                 fmt::format("give a record with `--data record.csv`, or define it in the model (`input {} = sin(t)`)", input));
}

Diagnostic simulation_stopped(std::string_view text) {
  return message("simulation-stopped", std::string(text), "check the parameter values and the initial state; the rows after the stop are NaN");
}

Diagnostic unknown_keyword(std::string_view function, std::string_view name, std::string_view nearest, std::string_view names) {
  return message("unknown-keyword", fmt::format("`{}()` has no setting `{}`", function, name),
                 nearest.empty() ? fmt::format("the settings are: {}", names)
                                 : fmt::format("did you mean `{}`? (the settings are: {})", nearest, names));
}

Diagnostic keyword_not_one_of(std::string_view name, std::string_view value, std::string_view choices) {
  return message("keyword-not-one-of", fmt::format("`{}={}` is not one of {}", name, value, choices));
}

Diagnostic keyword_wrong_type(std::string_view name, std::string_view given, std::string_view expected) {
  return message("keyword-wrong-type", fmt::format("`{}` is {}, not {}", name, given, expected));
}

Diagnostic array_lengths_differ(std::string_view record, std::string_view column, std::size_t length, std::string_view first,
                                std::size_t first_length) {
  return message("array-lengths-differ",
                 fmt::format("{}: column `{}` has {} values, column `{}` has {}", record, column, length, first, first_length),
                 "every column of a record is sampled at the same instants: give arrays of one length");
}

Diagnostic array_not_float(std::string_view record, std::string_view column, std::string_view dtype) {
  return message("array-not-float", fmt::format("{}: column `{}` holds {}, not floating-point numbers", record, column, dtype),
                 fmt::format("convert it, e.g. `{}.astype(float)`; float64 arrays are used without a conversion", column));
}

Diagnostic array_not_one_dimensional(std::string_view record, std::string_view column, std::size_t dimensions) {
  return message("array-not-one-dimensional", fmt::format("{}: column `{}` is a {}-dimensional array, not a 1-D one", record, column, dimensions),
                 "give each signal as its own 1-D array, e.g. {\"t\": t, \"y\": y}");
}

Diagnostic record_without_columns(std::string_view record) {
  return message("record-without-columns", fmt::format("{}: the record has no columns", record),
                 "give a dict of 1-D arrays named like the model's signals, e.g. {\"t\": t, \"x\": x, \"y\": y}");
}

Diagnostic not_a_record(std::string_view given) {
  return message("not-a-record", fmt::format("a record is a CSV path or a dict of 1-D arrays, not {}", given),
                 "give a path, a dict of arrays, or a list of either (several records)");
}

}  // namespace sidc::cli_diag
