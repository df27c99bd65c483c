#include "cli/fit_command.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli/exit_codes.hpp"
#include "cli/read_file.hpp"
#include "report/atomic_file.hpp"
#include "ir/compiled_model.hpp"
#include "compiler/pipeline.hpp"
#include "ir/print.hpp"
#include "ir/settings.hpp"
#include "diagnostics/model_catalogue.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/simulate/validate.hpp"
#include "report/fit_pictures.hpp"
#include "cli/record_options.hpp"

namespace sidc {
namespace {

namespace fs = std::filesystem;

struct FitArguments {
  std::vector<std::string> compiled;
  RecordArguments records;            // --data, --from, --to, --every, ... (record_options.hpp)
  std::string out;
  bool no_validate = false;
  std::vector<std::string> validate;  // further records, not used in fitting
  std::size_t validate_samples = 100000;  // compared at most per record (0 = all)
  std::string plots;                  // --plots DIR
  std::string report;                 // --report FILE.html
};

// The compiled model to fit when none is named: the most recently compiled *.sidc.json in the
// current directory, so that `sidc compile model.sid && sidc fit` fits that model.
std::optional<std::string> default_compiled_model(std::string& error) {
  std::vector<std::pair<fs::file_time_type, std::string>> found;
  for (const auto& entry : fs::directory_iterator(fs::current_path()))
    if (entry.is_regular_file() && entry.path().filename().string().ends_with(".sidc.json"))
      found.emplace_back(entry.last_write_time(), entry.path().filename().string());
  if (found.empty()) {
    error = "error: no compiled model (*.sidc.json) in this directory\nhint: run `sidc compile model.sid` first, or name one: `sidc fit model.sidc.json`";
    return std::nullopt;
  }
  std::sort(found.begin(), found.end());  // by time, then name: deterministic
  if (found.size() > 1) std::cerr << fmt::format("note: fitting `{}`, the most recently compiled model here\n", found.back().second);
  return found.back().second;
}

}  // namespace

std::optional<CompiledModel> load_compiled_model(const std::string& path, std::string& error) {
  auto text = read_whole_file(path, error);
  if (!text) return std::nullopt;
  if (path.ends_with(".sid")) {  // a model file: compiled here, in memory, nothing written
    auto source = std::make_shared<const SourceFile>(path, std::move(*text));
    CompileResult r = compile(source, {});
    if (!r.ok()) {
      error = r.diagnostics.render_all();
      if (!error.empty() && error.back() == '\n') error.pop_back();
      return std::nullopt;
    }
    std::cerr << r.diagnostics.render_all();  // warnings
    return compiled_model(source, *r.normalized, *r.integrated);
  }
  const nlohmann::ordered_json j = nlohmann::ordered_json::parse(*text, nullptr, false);
  if (j.is_discarded()) {
    error = fmt::format("error: `{}` is not JSON; compile the model again with `sidc compile`", path);
    return std::nullopt;
  }
  auto compiled = read_compiled_model(j, path, error);
  if (!compiled) return std::nullopt;
  // A model file changed since it was compiled makes a stale fit: say so.
  const fs::path source = fs::path(path).parent_path() / fs::path(compiled->source->name).filename();
  std::string ignored;
  if (auto now = read_whole_file(source.string(), ignored); now && source_hash(*now) != source_hash(compiled->source->text))
    std::cerr << fmt::format("warning: `{}` changed since `{}` was compiled\nhint: run `sidc compile {}` again\n", source.string(), path,
                             source.string());
  return compiled;
}

namespace {


nlohmann::ordered_json fit_json(const FitSummary& s, const CompiledModel& c, const std::string& compiled_path, const FitOptions& o) {
  using nlohmann::ordered_json;
  const ir::Model& m = c.integrated;
  ordered_json j;
  j["format"] = "sidc-fit";
  j["version"] = 1;
  j["sidc_version"] = SIDC_VERSION;
  j["model"] = m.name;
  j["compiled_model"] = compiled_path;
  j["source_hash"] = source_hash(c.source->text);
  j["settings"] = {{"derivative", {{"window", o.evaluation.derivative.window}, {"order", o.evaluation.derivative.polyorder}}},
                   {"second_derivative", o.evaluation.derivative.second == DerivativeOptions::Second::repeated ? "repeated" : "direct"},
                   {"edges", o.evaluation.derivative.edges == DerivativeOptions::Edges::drop ? "drop" : "shorten"},
                   {"integration", o.evaluation.integration.rule == IntegrationOptions::Rule::simpson ? "simpson" : "trapezoid"},
                   {"from", o.from ? ordered_json(*o.from) : ordered_json(nullptr)},
                   {"to", o.to ? ordered_json(*o.to) : ordered_json(nullptr)},
                   {"precision", to_string(o.least_squares.precision)}};
  ordered_json groups = ordered_json::array();
  for (const auto& g : s.groups) {
    const auto& ls = g.summary;
    ordered_json equations = ordered_json::array();
    for (std::size_t e : g.equations) equations.push_back({{"index", e + 1}, {"text", print(m.equations[e], m)}, {"integrations", m.equations[e].integrations}});
    ordered_json records = ordered_json::array();
    for (const auto& r : g.records) records.push_back({{"path", r.path}, {"t0", r.t0}, {"t_last", r.t_last}, {"step", r.step}, {"rows", r.rows}});
    ordered_json parameters = ordered_json::array();
    for (const auto& p : ls.parameters)
      parameters.push_back({{"name", p.name}, {"estimate", p.value}, {"standard_error", p.standard_error}, {"ci95", {p.ci_low, p.ci_high}}});
    ordered_json regions = ordered_json::array();
    for (const auto& r : g.regions) regions.push_back({{"guards", r.guards}, {"rows", r.rows}});
    ordered_json dependent = ordered_json::array();
    for (const auto& d : ls.dependent_groups) dependent.push_back(d);
    groups.push_back({{"equations", equations}, {"records", records}, {"regions", regions}, {"parameters", parameters},
                      {"statistics", {{"n", ls.n}, {"p", ls.p}, {"rank", ls.rank}, {"G", ls.G}, {"standard_error", ls.standard_error},
                                      {"residual_sd", ls.residual_sd}, {"r_squared", ls.r_squared}, {"aic", ls.aic}, {"bic", ls.bic},
                                      {"condition_before_scaling", ls.condition_before}, {"condition_after_scaling", ls.condition_after},
                                      {"digits_lost_estimate", ls.digits_lost_estimate}}},
                      {"termination", to_string(ls.termination)}, {"message", ls.message}, {"arithmetic", ls.arithmetic},
                      {"dependent_operations", dependent}});
  }
  j["groups"] = std::move(groups);
  return j;
}

// residuals.csv, written as the rows come: a streamed fit evaluates them again block by block
// (runtime/solve/fit.hpp, for_each_residual_block), so the file never has to be held in memory.
bool write_residuals(std::ostream& out, const ir::Model& model, const std::vector<SampledRecord>& records, const FitOptions& options,
                     const FitSummary& s, std::string& problem) {
  out << "group,equation,record,t,known,fitted,residual\n";
  fmt::memory_buffer buffer;
  for (std::size_t gi = 0; gi < s.groups.size(); ++gi) {
    const auto d = for_each_residual_block(model, records, options, s, gi, [&](std::span<const ResidualRow> rows) {
      buffer.clear();
      for (const auto& r : rows)
        fmt::format_to(std::back_inserter(buffer), "{},{},{},{},{},{},{}\n", gi + 1, r.equation + 1, records[r.record].path, r.time, r.known,
                       r.known - r.residual, r.residual);
      out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      return static_cast<bool>(out);
    });
    if (d) problem = render(*d);
    if (d || !out) return false;
  }
  return static_cast<bool>(out);
}

// Validation (thesis section 2-4, issue 5): the fitted equations solved and compared with each
// record. Skipped, with one line saying why, when the equations cannot be solved for their highest
// derivatives or the fit is not usable; never an error of the fit itself.
struct Validation {
  std::string note;  // why it was skipped; empty when it ran
  std::vector<ValidationSummary> runs;
  std::string method = "RK4, 4 steps per sample interval";
  std::size_t max_samples = 0;  // per record, 0 = all
  std::string failed_record;    // a --validate record that could not be compared: an error
};

Validation validate_fit(const CompiledModel& compiled, const FitSummary& summary, const std::vector<const SampledRecord*>& records,
                        std::size_t fitted_records, const FitOptions& options, std::size_t max_samples) {
  Validation v;
  v.max_samples = max_samples;
  if (!summary.is_solution_usable()) {
    v.note = "skipped: the fit is rank deficient, so its parameters are not worth simulating";
    return v;
  }
  const ir::Model& model = compiled.normalized;
  const auto& form = *compiled.explicit_form;
  if (auto* d = std::get_if<Diagnostic>(&form)) {
    v.note = "skipped: " + d->message;
    return v;
  }
  std::vector<double> parameters(model.parameters.size(), 0.0);
  for (const auto& g : summary.groups)
    for (const auto& p : g.summary.parameters)
      if (const int i = model.parameter_index(p.name); i >= 0) parameters[static_cast<std::size_t>(i)] = p.value;
  ValidationOptions o;
  o.derivative = options.evaluation.derivative;
  o.max_samples = max_samples;
  for (std::size_t r = 0; r < records.size(); ++r) {
    auto run = validate(model, std::get<ExplicitForm>(form), parameters, *records[r], o);
    if (auto* d = std::get_if<Diagnostic>(&run)) {
      if (r >= fitted_records) {  // a --validate record the user named: its problem is an error
        v.failed_record = fmt::format("error: cannot validate against `{}`: {}", records[r]->path, render(*d));
        return v;
      }
      v.note = fmt::format("skipped for `{}`: {}", records[r]->path, d->message);
      continue;
    }
    v.runs.push_back(std::get<ValidationSummary>(std::move(run)));
  }
  return v;
}

std::string validation_report(const Validation& v) {
  std::string out;
  if (!v.note.empty()) out += "\nvalidation: " + v.note + "\n";
  for (const auto& run : v.runs) {
    out += "\n" + run.report(v.method);
    if (run.truncated)
      out += fmt::format("  (the first {} samples only: --validate-samples N compares more, 0 all; about 16 equation evaluations a sample)\n",
                         v.max_samples);
  }
  return out;
}

nlohmann::ordered_json validation_json(const Validation& v) {
  using nlohmann::ordered_json;
  ordered_json j;
  j["method"] = v.method;
  j["note"] = v.note.empty() ? ordered_json(nullptr) : ordered_json(v.note);
  ordered_json runs = ordered_json::array();
  for (const auto& run : v.runs) {
    ordered_json outputs = ordered_json::array();
    for (const auto& r : run.outputs)
      outputs.push_back({{"output", r.output}, {"samples", r.samples}, {"max_abs_error", r.max_abs_error}, {"time_of_max_abs_error", r.time_of_max},
                         {"percent_error", r.percent_error}, {"fit_percent", r.fit_percent}, {"rms_error", r.rms_error}});
    ordered_json initial = ordered_json::object();
    for (const auto& [name, value] : run.initial_state) initial[name] = value;
    runs.push_back({{"record", run.record}, {"completed", run.simulation.completed()},
                    {"stopped_at", run.simulation.stopped_at ? ordered_json(*run.simulation.stopped_at) : ordered_json(nullptr)},
                    {"statement", run.statement}, {"initial_state", initial}, {"steps", run.simulation.steps}, {"outputs", outputs}});
  }
  j["records"] = std::move(runs);
  return j;
}

std::string validation_csv(const Validation& v) {
  if (v.runs.empty()) return {};
  std::string out = "record,t";
  for (const auto& name : v.runs.front().simulation.output_names) out += fmt::format(",{0}_recorded,{0}_simulated,{0}_error", name);
  out += "\n";
  for (const auto& run : v.runs)
    for (std::size_t i = 0; i < run.simulation.time.size(); ++i) {
      out += fmt::format("{},{}", run.record, run.simulation.time[i]);
      for (std::size_t j = 0; j < run.outputs.size(); ++j) out += fmt::format(",{},{},{}", run.recorded[j][i], run.simulated[j][i], run.error[j][i]);
      out += "\n";
    }
  return out;
}

// One model's fit, reported on stdout; its totals for a comparison table when asked.
struct ModelTotals {
  std::string name;
  std::string known;  // the known sides, printed: G(a) compares only models that share them
  std::size_t n = 0, p = 0;
  double G = 0;
  bool usable = false;
};

int fit_one(const std::string& compiled_path, const FitArguments& a, const std::string& out_dir, ModelTotals* totals) {
  std::string error;
  auto compiled = load_compiled_model(compiled_path, error);
  if (!compiled) {
    std::cerr << error << "\n";
    return exit_code::user_error;
  }
  const ir::Model& model = compiled->integrated;
  auto options = fit_options(model, a.records, error);
  if (!options) {
    std::cerr << error << "\n";
    return exit_code::usage_error;
  }

  auto loaded = load_records(*compiled, compiled_path, a.records, error);
  if (!loaded) {
    std::cerr << error << "\n";
    return exit_code::user_error;
  }
  const std::vector<ir::DataSource>& sources = loaded->sources;
  const std::vector<SampledRecord>& records = loaded->records;

  auto result = fit(model, records, *options);
  if (auto* d = std::get_if<Diagnostic>(&result)) {
    std::cerr << render(*d) << "\n";
    return exit_code::user_error;
  }
  const FitSummary& summary = std::get<FitSummary>(result);
  std::cout << fmt::format("sidc fit: model `{}` ({})\n\n", model.name, compiled_path) << summary.full_report(model);
  std::optional<Validation> validation;
  if (!a.no_validate) {
    // The fitted records, then those given only to be compared with (not copied: records can be long).
    std::vector<SampledRecord> extra;
    for (const auto& path : a.validate) {
      auto record = load_record(model, path, loaded->bind, error);
      if (!record) {
        std::cerr << error << "\n";
        return exit_code::user_error;
      }
      extra.push_back(std::move(*record));
    }
    std::vector<const SampledRecord*> checked;
    for (const auto& r : records) checked.push_back(&r);
    for (const auto& r : extra) checked.push_back(&r);
    validation = validate_fit(*compiled, summary, checked, records.size(), *options, a.validate_samples);
    if (!validation->failed_record.empty()) {
      std::cerr << validation->failed_record << "\n";
      return exit_code::user_error;
    }
    std::cout << validation_report(*validation);
  }
  const ResidualAnalysis residuals = analyse_residuals(model, summary, records, *options);
  std::cout << residual_report(residuals);
  if (!out_dir.empty()) {
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    const std::string json_path = (fs::path(out_dir) / "fit.json").string();
    const std::string csv_path = (fs::path(out_dir) / "residuals.csv").string();
    auto json = fit_json(summary, *compiled, compiled_path, *options);
    if (validation) json["validation"] = validation_json(*validation);
    json["residual_analysis"] = residual_json(residuals);
    const std::string validation_path = (fs::path(out_dir) / "validation.csv").string();
    const bool curves = validation && !validation->runs.empty();
    std::string problem;  // why residuals.csv could not be written, when the rows could not be had
    if (ec || !write_file_atomically(json_path, json.dump(1) + "\n", &error) ||
        !write_file_atomically(csv_path, [&](std::ostream& out) { return write_residuals(out, model, records, *options, summary, problem); }, &error) ||
        (curves && !write_file_atomically(validation_path, validation_csv(*validation), &error))) {
      if (!problem.empty()) error = problem;
      else if (!error.empty()) error = "error: " + error;
      // No half set of files: a fit.json without its residuals.csv would read as complete.
      std::error_code ignored;
      for (const auto& path : {json_path, csv_path, validation_path}) fs::remove(path, ignored);
      std::cerr << (error.empty() ? fmt::format("error: cannot create `{}`: {}", out_dir, ec.message()) : error) << "\n";
      return exit_code::user_error;
    }
    if (curves) std::cerr << "wrote " << json_path << ", " << csv_path << " and " << validation_path << "\n";
    else std::cerr << "wrote " << json_path << " and " << csv_path << "\n";
  }
  if (!a.plots.empty() || !a.report.empty()) {
    static const std::vector<ValidationSummary> none;
    const PictureContext context{*compiled, compiled_path, summary, *options, records, sources,
                                 validation ? validation->runs : none, validation ? validation->note : std::string("was switched off (--no-validate)"),
                                 residuals};
    std::vector<std::string> written;
    if (!write_fit_pictures(context, {a.plots, a.report}, written, error)) {
      std::cerr << error << "\n";
      return exit_code::user_error;
    }
    if (!a.plots.empty()) std::cerr << fmt::format("wrote {} pictures into {}\n", written.size() - (a.report.empty() ? 0 : 1), a.plots);
    if (!a.report.empty()) std::cerr << "wrote " << a.report << "\n";
  }
  // Last, so that a model whose files could not be written never ranks in the comparison table.
  if (totals) {
    totals->name = model.name.empty() ? compiled_path : model.name;
    totals->usable = summary.is_solution_usable();
    for (const auto& g : summary.groups) totals->n += g.summary.n, totals->p += g.summary.p, totals->G += g.summary.G;
    for (const auto& equation : model.equations) totals->known += print(equation.known) + "; ";
  }

  if (!summary.is_solution_usable()) {
    std::cerr << "error: the least-squares problem is rank deficient: some operations are (nearly) dependent (see the report)\n"
                 "hint: drop one operation of each dependent group, or give the record more excitation\n";
    return exit_code::user_error;
  }
  return exit_code::success;
}

// Section 2-1: "if the system equation has several alternate forms, that form which possesses a
// minimum sum of the squares of the residuals will constitute the solution of best fit". G(a)
// only compares forms fitted to the same rows with the same known side: the residuals of `= x`
// and of `= int(x)` are in different units. AIC and BIC also weigh the number of parameters.
std::string comparison_table(const std::vector<ModelTotals>& models) {
  std::string out = "\nmodel comparison (thesis Table 4-1.2; smaller is better in the last four columns):\n";
  out += fmt::format("  {:<28} {:>6} {:>4} {:>14} {:>12} {:>11} {:>11}\n", "model", "n", "p", "G(a)", "sqrt(G/n)", "AIC", "BIC");
  const bool same_rows = std::all_of(models.begin(), models.end(), [&](const ModelTotals& m) { return m.n == models.front().n; });
  const bool same_known = std::all_of(models.begin(), models.end(), [&](const ModelTotals& m) { return m.known == models.front().known; });
  double best_g = INFINITY, best_aic = INFINITY, best_bic = INFINITY;
  std::vector<std::array<double, 2>> criteria;
  for (const auto& m : models) {
    const double n = static_cast<double>(m.n), k = static_cast<double>(m.p);
    const double aic = n * std::log(m.G / n) + 2 * k, bic = n * std::log(m.G / n) + k * std::log(n);
    criteria.push_back({aic, bic});
    if (m.usable) best_g = std::min(best_g, m.G), best_aic = std::min(best_aic, aic), best_bic = std::min(best_bic, bic);
  }
  for (std::size_t i = 0; i < models.size(); ++i) {
    const auto& m = models[i];
    std::string marks;
    if (m.usable && same_known && same_rows && m.G == best_g) marks += " least G";
    if (m.usable && same_known && criteria[i][0] == best_aic) marks += " best AIC";
    if (m.usable && same_known && criteria[i][1] == best_bic) marks += " best BIC";
    if (!m.usable) marks = " (rank deficient)";
    out += fmt::format("  {:<28} {:>6} {:>4} {:>14.6g} {:>12.4g} {:>11.4g} {:>11.4g}{}\n", m.name, m.n, m.p, m.G,
                       std::sqrt(m.G / static_cast<double>(m.n)), criteria[i][0], criteria[i][1], marks);
  }
  if (!same_known)
    out += "  (the models' known sides differ, as between a derivative and an integrated form, so their residuals\n"
           "   are in different units: neither G(a) nor AIC and BIC rank them; compare them by their parameters)\n";
  else if (!same_rows)
    out += "  (the models were fitted to different numbers of rows, so G(a) does not rank them; AIC and BIC do)\n";
  return out;
}

int run_fit(const FitArguments& a) {
  std::string error;
  std::vector<std::string> compiled_paths = a.compiled;
  if (compiled_paths.empty()) {
    auto found = default_compiled_model(error);
    if (!found) {
      std::cerr << error << "\n";
      return exit_code::user_error;
    }
    compiled_paths.push_back(*found);
  }
  if (compiled_paths.size() == 1) return fit_one(compiled_paths.front(), a, a.out, nullptr);
  if (!a.plots.empty() || !a.report.empty()) {
    std::cerr << "error: --plots and --report draw one model's fit, and " << compiled_paths.size() << " models were given\n"
              << "hint: fit the models together for the comparison table, and each alone with --plots or --report\n";
    return exit_code::usage_error;
  }
  std::vector<ModelTotals> totals;
  int status = exit_code::success;
  for (const auto& path : compiled_paths) {
    ModelTotals t;
    const std::string out = a.out.empty() ? "" : (fs::path(a.out) / fs::path(path).stem().stem()).string();
    const int code = fit_one(path, a, out, &t);
    if (code != exit_code::success && t.n == 0) return code;  // could not be fitted at all
    totals.push_back(t);
    std::cout << "\n";
    status = std::max(status, code == exit_code::user_error && t.n > 0 ? exit_code::success : code);
  }
  std::cout << comparison_table(totals);
  return status;
}


}  // namespace

void add_fit_command(CLI::App& app, int& exit_status) {
  auto a = std::make_shared<FitArguments>();
  CLI::App* cmd = app.add_subcommand("fit", "Determine the parameters of a compiled model from records (thesis section 2-1)");
  cmd->add_option("compiled", a->compiled, "Compiled model(s) (.sidc.json), or model files (.sid) to compile first; default: the most recent compiled model here");
  add_record_options(cmd, a->records);
  cmd->add_option("--out", a->out, "Directory for fit.json, residuals.csv and validation.csv");
  cmd->add_option("--validate-samples", a->validate_samples, "Samples of each record compared by simulation at most, from the start (0 = all)");
  cmd->add_option("--plots", a->plots, "Directory for the pictures (SVG and PNG, drawn by gnuplot): outputs, errors, functions, residual tests");
  cmd->add_option("--report", a->report, "Write a one-page HTML report with the fit's tables and pictures to this file");
  auto* no_validate = cmd->add_flag("--no-validate", a->no_validate, "Do not solve the fitted equations and compare them with the records (thesis section 2-4)");
  cmd->add_option("--validate", a->validate, "Also compare the solved fitted equations with this record, not used in fitting (repeatable)")
      ->allow_extra_args(false)
      ->excludes(no_validate);
  cmd->callback([a, &exit_status] { exit_status = run_fit(*a); });
}

}  // namespace sidc
