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
#include "compiler/compiled_model.hpp"
#include "compiler/pipeline.hpp"
#include "compiler/print.hpp"
#include "compiler/settings.hpp"
#include "grammar/diagnostic_catalogue.hpp"
#include "runtime/bind_record.hpp"
#include "runtime/fit.hpp"

namespace sidc {
namespace {

namespace fs = std::filesystem;

struct FitArguments {
  std::vector<std::string> compiled;
  std::vector<std::string> data;
  std::optional<double> from, to, step, resample;
  std::optional<int> every;
  std::string derivative, second_derivative, edges, integration, precision;
  std::string out;
  std::string weights;
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

std::optional<CompiledModel> load_compiled(const std::string& path, std::string& error) {
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
    return CompiledModel{source, *r.normalized, *r.integrated};
  }
  const nlohmann::ordered_json j = nlohmann::ordered_json::parse(*text, nullptr, false);
  if (j.is_discarded()) {
    error = fmt::format("error: `{}` is not JSON; compile the model again with `sidc compile`", path);
    return std::nullopt;
  }
  auto compiled = compiled_model_from_json(j, path, error);
  if (!compiled) return std::nullopt;
  // A model file changed since it was compiled makes a stale fit: say so.
  const fs::path source = fs::path(path).parent_path() / fs::path(compiled->source->name).filename();
  std::string ignored;
  if (auto now = read_whole_file(source.string(), ignored); now && source_hash(*now) != source_hash(compiled->source->text))
    std::cerr << fmt::format("warning: `{}` changed since `{}` was compiled\nhint: run `sidc compile {}` again\n", source.string(), path,
                             source.string());
  return compiled;
}

// Settings from the model file, overridden by the command line.
std::optional<FitOptions> fit_options(const ir::Model& model, const FitArguments& a, std::string& error) {
  const EvaluationSettings e = evaluation_settings(model.settings);
  FitOptions o;
  MovingArc arc = e.derivative;
  if (!a.derivative.empty()) {
    auto parsed = parse_moving_arc(a.derivative);
    if (!parsed) {
      error = fmt::format("error: `--derivative {}` is not a moving-arc operator\nhint: write e.g. `--derivative \"savgol(7, 3)\"`", a.derivative);
      return std::nullopt;
    }
    arc = *parsed;
  }
  o.evaluation.derivative.window = arc.window;
  o.evaluation.derivative.polyorder = arc.order;
  bool repeated = e.second_derivative_repeated, shorten = e.shorten_edges, trapezoid = e.trapezoid;
  if (!a.second_derivative.empty()) repeated = a.second_derivative == "repeated";
  if (!a.edges.empty()) shorten = a.edges == "shorten";
  if (!a.integration.empty()) trapezoid = a.integration == "trapezoid";
  o.evaluation.derivative.second = repeated ? DerivativeOptions::Second::repeated : DerivativeOptions::Second::direct;
  o.evaluation.derivative.edges = shorten ? DerivativeOptions::Edges::shorten : DerivativeOptions::Edges::drop;
  o.evaluation.integration.rule = trapezoid ? IntegrationOptions::Rule::trapezoid : IntegrationOptions::Rule::simpson;
  if (e.smooth_before_integration) {
    o.evaluation.integration.smoothing_window = e.smooth_before_integration->window;
    o.evaluation.integration.smoothing_polyorder = e.smooth_before_integration->order;
  }
  o.from = a.from ? a.from : e.from;
  o.to = a.to ? a.to : e.to;
  if (a.precision == "double") o.least_squares.precision = Precision::double_precision;
  if (a.precision == "extended") o.least_squares.precision = Precision::extended;
  if (!o.is_valid(&error)) {
    error = "error: " + error;
    return std::nullopt;
  }
  return o;
}

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

std::string residuals_csv(const FitSummary& s) {
  std::string out = "group,equation,record,t,known,fitted,residual\n";
  for (std::size_t gi = 0; gi < s.groups.size(); ++gi) {
    const auto& g = s.groups[gi];
    for (std::size_t i = 0; i < g.row_time.size(); ++i) {
      const double r = i < g.summary.residuals.size() ? g.summary.residuals[i] : std::numeric_limits<double>::quiet_NaN();
      out += fmt::format("{},{},{},{},{},{},{}\n", gi + 1, g.row_equation[i] + 1, g.records[g.row_record[i]].path, g.row_time[i], g.known[i],
                         g.known[i] - r, r);
    }
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
  auto compiled = load_compiled(compiled_path, error);
  if (!compiled) {
    std::cerr << error << "\n";
    return exit_code::user_error;
  }
  const ir::Model& model = compiled->integrated;
  auto options = fit_options(model, a, error);
  if (!options) {
    std::cerr << error << "\n";
    return exit_code::usage_error;
  }

  // Records: from the command line, else the model's data statements (paths relative to the model).
  std::vector<ir::DataSource> sources;
  const fs::path base = fs::path(compiled_path).parent_path();
  if (!a.data.empty()) {
    for (const auto& path : a.data) {
      ir::DataSource s = model.data.empty() ? ir::DataSource{} : model.data.front();
      s.path = path;
      sources.push_back(std::move(s));
    }
  } else {
    for (auto s : model.data) {
      if (fs::path(s.path).is_relative()) s.path = (base / s.path).lexically_normal().string();
      sources.push_back(std::move(s));
    }
  }
  if (sources.empty()) {
    std::cerr << render(diag::no_data_file(Span{compiled->source, 0, 0})) << "\n";
    return exit_code::user_error;
  }
  const EvaluationSettings e = evaluation_settings(model.settings);
  BindOptions bind;
  bind.every = a.every.value_or(e.every);
  bind.step = a.step ? a.step : e.step;
  bind.resample = a.resample;
  if (!a.weights.empty()) bind.weights = a.weights;
  else bind.weights = e.weights;
  std::vector<SampledRecord> records;
  for (const auto& s : sources) {
    auto record = read_csv(s.path);
    if (auto* d = std::get_if<Diagnostic>(&record)) {
      std::cerr << render(*d) << "\n";
      return exit_code::user_error;
    }
    auto bound = bind_record(std::get<Record>(record), s, model, bind);
    if (auto* d = std::get_if<Diagnostic>(&bound)) {
      std::cerr << render(*d) << "\n";
      return exit_code::user_error;
    }
    records.push_back(std::get<SampledRecord>(std::move(bound)));
  }

  auto result = fit(model, records, *options);
  if (auto* d = std::get_if<Diagnostic>(&result)) {
    std::cerr << render(*d) << "\n";
    return exit_code::user_error;
  }
  const FitSummary& summary = std::get<FitSummary>(result);
  std::cout << fmt::format("sidc fit: model `{}` ({})\n\n", model.name, compiled_path) << summary.full_report(model);
  if (totals) {
    totals->name = model.name.empty() ? compiled_path : model.name;
    totals->usable = summary.is_solution_usable();
    for (const auto& g : summary.groups) totals->n += g.summary.n, totals->p += g.summary.p, totals->G += g.summary.G;
    for (const auto& equation : model.equations) totals->known += print(equation.known) + "; ";
  }

  if (!out_dir.empty()) {
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    const std::string json_path = (fs::path(out_dir) / "fit.json").string();
    const std::string csv_path = (fs::path(out_dir) / "residuals.csv").string();
    if (ec || !write_file_atomically(json_path, fit_json(summary, *compiled, compiled_path, *options).dump(1) + "\n", error) ||
        !write_file_atomically(csv_path, residuals_csv(summary), error)) {
      std::cerr << (error.empty() ? fmt::format("error: cannot create `{}`: {}", out_dir, ec.message()) : error) << "\n";
      return exit_code::user_error;
    }
    std::cerr << "wrote " << json_path << " and " << csv_path << "\n";
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

// CLI11's own range check prints the whole range of a double; say it plainly.
const CLI::Validator positive = CLI::Validator(
    [](std::string& value) -> std::string {
      double x = 0;
      const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), x);
      if (ec != std::errc() || end != value.data() + value.size() || !(x > 0) || !std::isfinite(x))
        return "`" + value + "` is not a positive number";
      return {};
    },
    "POSITIVE");

}  // namespace

void add_fit_command(CLI::App& app, int& exit_status) {
  auto a = std::make_shared<FitArguments>();
  CLI::App* cmd = app.add_subcommand("fit", "Determine the parameters of a compiled model from records (thesis section 2-1)");
  cmd->add_option("compiled", a->compiled, "Compiled model(s) (.sidc.json), or model files (.sid) to compile first; default: the most recent compiled model here");
  cmd->add_option("--data", a->data, "Record(s) to fit instead of the model's data statements (CSV)");
  cmd->add_option("--from", a->from, "Start of the fit window (time)");
  cmd->add_option("--to", a->to, "End of the fit window (time)");
  cmd->add_option("--every", a->every, "Keep every K-th sample")->check(positive);
  cmd->add_option("--step", a->step, "Sampling step, for records without a time column")->check(positive);
  cmd->add_option("--resample", a->resample, "Interpolate the record linearly onto this uniform step")->check(positive);
  cmd->add_option("--derivative", a->derivative, "Moving-arc operator, e.g. \"savgol(7, 3)\"");
  cmd->add_option("--second-derivative", a->second_derivative, "repeated (eq. 3-1.8) or direct")->check(CLI::IsMember({"repeated", "direct"}));
  cmd->add_option("--edges", a->edges, "drop (the thesis) or shorten")->check(CLI::IsMember({"drop", "shorten"}));
  cmd->add_option("--integration", a->integration, "simpson or trapezoid")->check(CLI::IsMember({"simpson", "trapezoid"}));
  cmd->add_option("--precision", a->precision, "Least-squares arithmetic: automatic, double or extended")
      ->check(CLI::IsMember({"automatic", "double", "extended"}));
  cmd->add_option("--weights", a->weights, "A record column weighting each row's residual (eq. 2-1.6)");
  cmd->add_option("--out", a->out, "Directory for fit.json and residuals.csv");
  cmd->callback([a, &exit_status] { exit_status = run_fit(*a); });
}

}  // namespace sidc
