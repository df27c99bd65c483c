#include "report/fit_files.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>

#include "diagnostics/cli_catalogue.hpp"
#include "ir/print.hpp"
#include "ir/queries.hpp"
#include "report/atomic_file.hpp"
#include "report/csv_field.hpp"

namespace sidc {
namespace fs = std::filesystem;

namespace {

// residuals.csv, written as the rows come: a streamed fit evaluates them again block by block
// (runtime/solve/fit.hpp, for_each_residual_block), so the file never has to be held in memory.
bool write_residuals(std::ostream& out, const ir::Model& model, const std::vector<SampledRecord>& records, const FitOptions& options,
                     const FitSummary& s, std::optional<Diagnostic>& problem) {
  out << "group,equation,record,t,known,fitted,residual\n";
  std::vector<std::string> paths;  // each record's path as a CSV field, made once
  for (const auto& r : records) paths.push_back(csv_field(r.path));
  fmt::memory_buffer buffer;
  for (std::size_t gi = 0; gi < s.groups.size(); ++gi) {
    const auto d = for_each_residual_block(model, records, options, s, gi, [&](std::span<const ResidualRow> rows) {
      buffer.clear();
      for (const auto& r : rows)
        fmt::format_to(std::back_inserter(buffer), "{},{},{},{},{},{},{}\n", gi + 1, r.equation + 1, paths[r.record], r.time, r.known,
                       r.known - r.residual, r.residual);
      out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      return static_cast<bool>(out);
    });
    if (d) problem = *d;
    if (d || !out) return false;
  }
  return static_cast<bool>(out);
}

}  // namespace

bool write_local_csv(std::ostream& out, const LocalFitSummary& local) {
  if (local.groups.empty()) return static_cast<bool>(out);
  const std::size_t records = local.groups.front().records.size();
  const bool several_groups = local.groups.size() > 1;
  out << (records > 1 ? "record," : "") << "t_center";
  for (std::size_t g = 0; g < local.groups.size(); ++g) {
    for (const auto& name : local.groups[g].columns) out << "," << name << "," << name << "_se";
    const std::string suffix = several_groups ? fmt::format("_{}", g + 1) : "";
    out << ",G" << suffix << ",n" << suffix << ",rank" << suffix;
  }
  out << "\n";
  // Windows [first, last) of record r as text: shortest round-trip numbers, an empty cell where a
  // window has no estimate (its rank says why).
  auto format = [&](std::size_t r, std::size_t first, std::size_t last, fmt::memory_buffer& buffer) {
    buffer.clear();
    auto put = [&](double v) {
      if (std::isfinite(v)) fmt::format_to(fmt::appender(buffer), ",{}", v);
      else buffer.push_back(',');
    };
    const LocalRecordFit& front = local.groups.front().records[r];
    const std::string path = records > 1 ? csv_field(front.path) : std::string();
    for (std::size_t k = first; k < last; ++k) {
      if (records > 1) fmt::format_to(fmt::appender(buffer), "{},", path);
      fmt::format_to(fmt::appender(buffer), "{}", front.t_center[k]);
      for (const auto& g : local.groups) {
        const LocalRecordFit& fit = g.records[r];
        const std::size_t p = g.columns.size();
        for (std::size_t j = 0; j < p; ++j) {
          put(fit.estimates[k * p + j]);
          put(fit.standard_errors[k * p + j]);
        }
        put(fit.G[k]);
        fmt::format_to(fmt::appender(buffer), ",{},{}", fit.n[k], fit.rank[k]);
      }
      buffer.push_back('\n');
    }
  };
  // Written a chunk of windows at a time (a 10^6-window file is hundreds of MB). Formatting the
  // chunks on several cores was tried: the write and the sync, not the formatting, set the time.
  constexpr std::size_t kChunk = 4096;
  fmt::memory_buffer buffer;
  for (std::size_t r = 0; r < records; ++r) {
    const std::size_t windows = local.groups.front().records[r].windows();
    for (std::size_t first = 0; first < windows; first += kChunk) {
      format(r, first, std::min(windows, first + kChunk), buffer);
      out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      if (!out) return false;
    }
  }
  return static_cast<bool>(out);
}

nlohmann::ordered_json local_json(const LocalFitSummary& l) {
  using nlohmann::ordered_json;
  ordered_json records = ordered_json::array();
  if (!l.groups.empty())
    for (const auto& r : l.groups.front().records)
      records.push_back({{"record", r.path}, {"windows", r.windows()}, {"window_samples", r.window_samples}});
  return {{"width", l.options.forget ? ordered_json(nullptr) : ordered_json(l.options.width)},
          {"stride", l.options.stride},
          {"forget", l.options.forget ? ordered_json(*l.options.forget) : ordered_json(nullptr)},
          {"records", std::move(records)},
          {"rank_deficient_windows", l.rank_deficient},
          {"fresh_factors", l.fresh_factors},
          {"refused_downdates", l.refused_downdates},
          {"border_checks", l.drift_checks},
          {"largest_relative_difference_updated_vs_fresh", l.max_drift},
          {"file", "local.csv"}};
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
  // The model's text itself, so that `sidc export fit.json` needs nothing else to write the
  // fitted equations as code.
  j["model_source"] = c.source->text;
  const ordered_json derivative = o.evaluation.automatic_derivative
                                      ? ordered_json{{"window", "auto"}, {"order", "auto"}}
                                      : ordered_json{{"window", o.evaluation.derivative.window}, {"order", o.evaluation.derivative.polyorder}};
  j["settings"] = {{"derivative", derivative},
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
    for (std::size_t e : g.equations) equations.push_back({{"index", e + 1}, {"text", print(m.equations[e], m)}, {"integrations", m.equations[e].integrations},
                                                     {"form", m.equations[e].weak ? "weak" : m.equations[e].integrations ? "integrated" : "derivative"}});
    ordered_json records = ordered_json::array();
    for (std::size_t r = 0; r < g.records.size(); ++r) {
      const auto& rec = g.records[r];
      records.push_back({{"path", rec.path}, {"t0", rec.t0}, {"t_last", rec.t_last}, {"step", rec.step}, {"rows", rec.rows}});
      if (r < g.subdomains.size()) records.back()["weak_subdomains"] = g.subdomains[r];
    }
    ordered_json parameters = ordered_json::array();
    for (std::size_t k = 0; k < ls.parameters.size(); ++k) {
      const auto& p = ls.parameters[k];
      parameters.push_back({{"name", p.name}, {"estimate", p.value}, {"standard_error", p.standard_error}, {"ci95", {p.ci_low, p.ci_high}}});
      // Newey-West (runtime/solve/hac_covariance.hpp): only where computed, beside the classical ones.
      if (g.hac.computed && k < g.hac.standard_errors.size()) {
        parameters.back()["hac_standard_error"] = g.hac.standard_errors[k];
        parameters.back()["hac_ci95"] = {g.hac.ci_low[k], g.hac.ci_high[k]};
      }
      // Only for models that give units (docs/language.md, "Units"): other files stay as they were.
      if (const std::string unit = parameter_unit(m, p.name); !unit.empty()) parameters.back()["unit"] = unit;
    }
    // The parameters' covariance sigma^2 (R^T R)^-1 (MATLAB's getcov) and its correlation, in
    // the order of `parameters`; a parameter that is not estimable has NaN in its row and column.
    ordered_json covariance = ordered_json::array(), correlation = ordered_json::array();
    const auto& cov = ls.covariance;
    for (Eigen::Index a = 0; a < cov.rows(); ++a) {
      ordered_json cov_row = ordered_json::array(), corr_row = ordered_json::array();
      for (Eigen::Index b = 0; b < cov.cols(); ++b) {
        cov_row.push_back(cov(a, b));
        corr_row.push_back(a == b && std::isfinite(cov(a, a)) && cov(a, a) > 0 ? 1.0 : cov(a, b) / std::sqrt(cov(a, a) * cov(b, b)));
      }
      covariance.push_back(std::move(cov_row));
      correlation.push_back(std::move(corr_row));
    }
    ordered_json regions = ordered_json::array();
    for (const auto& r : g.regions) regions.push_back({{"guards", r.guards}, {"rows", r.rows}});
    ordered_json dependent = ordered_json::array();
    for (const auto& d : ls.dependent_groups) dependent.push_back(d);
    ordered_json drift = ordered_json::array();
    for (const auto& d : g.drift)
      drift.push_back({{"equation", d.equation + 1}, {"what", d.what}, {"operation", d.operation}, {"record", d.record},
                       {"degree", d.degree}, {"share", d.share}});
    groups.push_back({{"equations", equations}, {"records", records}, {"regions", regions}, {"parameters", parameters},
                      {"covariance", covariance}, {"correlation", correlation},
                      {"statistics", {{"n", ls.n}, {"p", ls.p}, {"rank", ls.rank}, {"G", ls.G}, {"standard_error", ls.standard_error},
                                      {"residual_sd", ls.residual_sd}, {"r_squared", ls.r_squared},
                                      {"r_squared_uncentred", ls.uncentred_r_squared}, {"r_squared_centred", ls.centred_r_squared}, {"aic", ls.aic}, {"bic", ls.bic},
                                      {"condition_before_scaling", ls.condition_before}, {"condition_after_scaling", ls.condition_after},
                                      {"digits_lost_estimate", ls.digits_lost_estimate}}},
                      {"termination", to_string(ls.termination)}, {"message", ls.message}, {"arithmetic", ls.arithmetic},
                      {"dependent_operations", dependent}, {"drift", drift}});
    if (!g.subdomains.empty())
      groups.back()["weak_weighting"] = {{"covariance", g.weak_weighting.applied}, {"solves", g.weak_weighting.iterations},
                                         {"residual_variance", g.weak_weighting.residual_variance}, {"note", g.weak_weighting.note}};
    if (g.hac.computed)
      groups.back()["hac"] = {{"bandwidth", g.hac.bandwidth}, {"lag1_autocorrelation", g.hac.lag1_autocorrelation}, {"band99", g.hac.band},
                              {"prewhitening_clamped", g.hac.prewhitening_clamped}};
    else if (!g.hac.note.empty())
      groups.back()["hac"] = {{"note", g.hac.note}};
  }
  j["groups"] = std::move(groups);
  ordered_json noise = ordered_json::array();
  for (const auto& r : s.operators) {
    ordered_json signals = ordered_json::array();
    for (const auto& n : r.noise)
      signals.push_back({{"signal", n.signal}, {"column", n.column}, {"sigma", n.level.sigma}, {"spread", n.level.spread},
                         {"relative", n.level.relative()}, {"difference_order", n.level.difference_order}, {"constant", n.level.constant},
                         {"noise_exceeds_variation", n.level.exceeds_variation()}});
    ordered_json arcs = ordered_json::array();
    for (const auto& a : r.arcs)
      arcs.push_back({{"signal", a.signal}, {"order", a.order}, {"window", a.arc.window}, {"polynomial_order", a.arc.polyorder},
                      {"form", a.order >= 2 && a.arc.second == DerivativeOptions::Second::repeated ? "repeated" : "direct"},
                      {"estimated_rms_error", a.rms_error()}, {"bias", a.bias}, {"noise", a.noise}, {"noise_free", a.noise_free}});
    ordered_json warnings = ordered_json::array();
    for (const auto& w : r.warnings) warnings.push_back({{"code", w.code}, {"message", w.message}});
    noise.push_back({{"path", r.record}, {"signals", signals}, {"derivative_operators", r.automatic ? arcs : ordered_json(nullptr)},
                     {"warnings", warnings}});
  }
  j["records"] = std::move(noise);
  return j;
}

nlohmann::ordered_json residual_json(const ResidualAnalysis& analysis) {
  using nlohmann::ordered_json;
  auto curve = [](const CorrelationCurve& c) {
    return ordered_json{{"name", c.name}, {"computed", c.computed}, {"white", c.white}, {"verdict", c.verdict},
                        {"lags", c.lags}, {"values", c.values}, {"lags_outside_band", c.lags_outside}};
  };
  ordered_json groups = ordered_json::array();
  for (std::size_t g = 0; g < analysis.groups.size(); ++g) {
    const auto& rc = analysis.groups[g];
    if (!analysis.notes[g].empty()) {
      groups.push_back({{"computed", false}, {"note", analysis.notes[g]}});
      continue;
    }
    const bool truncated = g < analysis.truncated.size() && analysis.truncated[g];
    ordered_json cross = ordered_json::array();
    for (const auto& c : rc.cross) cross.push_back(curve(c));
    groups.push_back({{"computed", true}, {"rows_used", truncated ? ordered_json(kMaxResidualRows) : ordered_json("all")}, {"n", rc.n}, {"segments", rc.segments}, {"max_lag", rc.max_lag},
                      {"confidence_level", rc.confidence_level}, {"band", rc.band}, {"residuals_white", rc.residuals_white},
                      {"verdict", rc.verdict}, {"autocorrelation", curve(rc.autocorrelation)}, {"cross_correlation", cross},
                      {"intervals_to_trust", g < analysis.trust_newey_west.size() && analysis.trust_newey_west[g] ? "newey_west" : "classical"}});
  }
  return groups;
}

nlohmann::ordered_json instrumental_variables_json(const InstrumentalVariablesSummary& iv) {
  using nlohmann::ordered_json;
  auto optional = [](const std::optional<double>& x) { return x ? ordered_json(*x) : ordered_json(nullptr); };
  ordered_json groups = ordered_json::array();
  for (const auto& g : iv.groups) {
    ordered_json parameters = ordered_json::array();
    for (const auto& p : g.parameters) {
      parameters.push_back({{"name", p.name}, {"estimate", p.value}, {"standard_error", p.standard_error}, {"ci95", {p.ci_low, p.ci_high}},
                            {"equation_error_estimate", p.equation_error}});
      if (g.hac) {
        parameters.back()["hac_standard_error"] = p.hac_standard_error;
        parameters.back()["hac_ci95"] = {p.hac_ci_low, p.hac_ci_high};
      }
      if (!p.unit.empty()) parameters.back()["unit"] = p.unit;
    }
    groups.push_back({{"form", g.form}, {"n", g.n}, {"p", g.p}, {"residual_sd", g.residual_sd}, {"parameters", std::move(parameters)}});
    if (g.hac)
      groups.back()["hac"] = {{"bandwidth", g.hac_bandwidth}, {"lag1_autocorrelation", g.lag1}, {"band99", g.band}};
    else if (!g.hac_note.empty())
      groups.back()["hac"] = {{"note", g.hac_note}};
  }
  return {{"termination", to_string(iv.termination)}, {"statement", iv.statement}, {"iterations", iv.iterations},
          {"max_iterations", iv.max_iterations}, {"tolerance", iv.tolerance}, {"changes", iv.changes},
          {"fit_percent", optional(iv.fit_percent)}, {"equation_error_fit_percent", optional(iv.equation_error_fit_percent)},
          {"groups", std::move(groups)}};
}

nlohmann::ordered_json noise_check_json(const NoiseCheck& check) {
  using nlohmann::ordered_json;
  if (!check.ran) return {{"ran", false}, {"statement", check.statement()}};
  ordered_json parameters = ordered_json::array();
  for (const auto& s : check.shifts)
    parameters.push_back({{"name", s.name}, {"estimate", s.estimate}, {"standard_error", s.standard_error}, {"copies_sd", s.scatter},
                          {"shift", s.shift}, {"shift_error", s.shift_error}, {"too_narrow", s.narrow}, {"biased", s.biased}});
  return {{"ran", true}, {"replicates", check.replicates}, {"statement", check.statement()}, {"parameters", std::move(parameters)}};
}

nlohmann::ordered_json validation_json(const FitValidation& v, std::size_t fitted_records) {
  using nlohmann::ordered_json;
  ordered_json j;
  j["method"] = v.method;
  j["note"] = v.note.empty() ? ordered_json(nullptr) : ordered_json(v.note);
  ordered_json runs = ordered_json::array();
  for (std::size_t i = 0; i < v.runs.size(); ++i) {
    const auto& run = v.runs[i];
    ordered_json outputs = ordered_json::array(), verdict = ordered_json::array();
    auto optional = [](const std::optional<double>& x) { return x ? ordered_json(*x) : ordered_json(nullptr); };
    for (const auto& r : run.outputs) {
      outputs.push_back({{"output", r.output}, {"samples", r.samples}, {"max_abs_error", r.max_abs_error}, {"time_of_max_abs_error", r.time_of_max},
                         {"percent_error", r.percent_error}, {"fit_percent", r.fit_percent}, {"rms_error", r.rms_error}});
      verdict.push_back({{"output", r.output}, {"fit_percent", r.fit_percent}, {"follows", r.follows}, {"departs_at", optional(r.departs_at)},
                         {"max_error", r.max_abs_error}, {"time_of_max_error", r.time_of_max}});
    }
    auto state = [](const std::vector<std::pair<std::string, double>>& named) {
      ordered_json o = ordered_json::object();
      for (const auto& [name, value] : named) o[name] = value;
      return o;
    };
    const bool estimated = run.initial_method == InitialState::estimate && run.start_segment > 0;
    ordered_json restarted = nullptr;  // validate.hpp, kRestartPeriods: the sensitivity test, when made
    if (const auto& r = run.restarted) {
      ordered_json fits = ordered_json::array();
      for (const auto& [output, fit] : r->fit_percent) fits.push_back({{"output", output}, {"fit_percent", fit}});
      restarted = {{"free_run_departs_at", r->free_run_departs_at}, {"separates_at", optional(r->separates_at)},
                   {"start_unfitted", r->start_unfitted}, {"sensitive", r->sensitive},
                   {"fastest_period", r->period}, {"judged", r->judged},
                   {"runs", r->runs}, {"run_duration", r->runs ? ordered_json(r->run_duration) : ordered_json(nullptr)},
                   {"run_every", r->runs ? ordered_json(r->run_every) : ordered_json(nullptr)},
                   {"compared_share", r->runs ? ordered_json(r->compared_share) : ordered_json(nullptr)},
                   {"completed", r->completed}, {"follows", r->follows}, {"outputs", fits}};
    }
    runs.push_back({{"record", run.record}, {"held_out", i >= fitted_records}, {"completed", run.simulation.completed()},
                    {"stopped_at", optional(run.simulation.stopped_at)},
                    {"statement", run.statement},
                    {"verdict", {{"follows", run.follows}, {"threshold_fit_percent", kFollowsFitPercent}, {"departure_share", kDepartureShare},
                                 {"outputs", verdict}, {"restarted", restarted}}},
                    {"initial_state", state(run.initial_state)}, {"initial_state_method", estimated ? "estimate" : "record"},
                    {"initial_state_from_record", state(run.recorded_state)},
                    {"start_segment_samples", estimated ? ordered_json(run.start_segment) : ordered_json(nullptr)},
                    {"steps", run.simulation.steps}, {"outputs", outputs}});
  }
  j["records"] = std::move(runs);
  return j;
}

std::string validation_csv(const FitValidation& v) {
  if (v.runs.empty()) return {};
  std::string out = "record,t";
  for (const auto& name : v.runs.front().simulation.output_names) out += fmt::format(",{0}_recorded,{0}_simulated,{0}_error", name);
  out += "\n";
  for (const auto& run : v.runs)
    for (std::size_t i = 0; i < run.simulation.time.size(); ++i) {
      out += fmt::format("{},{}", csv_field(run.record), run.simulation.time[i]);
      for (std::size_t j = 0; j < run.outputs.size(); ++j) {
        const double y = run.recorded[j][i], yhat = run.simulation.outputs[j][i];
        out += fmt::format(",{},{},{}", y, yhat, y - yhat);  // E, eq. 4-1.4
      }
      out += "\n";
    }
  return out;
}

void non_finite_as_strings(nlohmann::ordered_json& j) {
  if (j.is_number_float()) {
    const double v = j.get<double>();
    if (std::isnan(v)) j = "nan";
    else if (std::isinf(v)) j = v > 0 ? "inf" : "-inf";
  } else if (j.is_structured()) {
    for (auto& child : j) non_finite_as_strings(child);
  }
}

namespace {

// NaN (an interval Gauss-Newton could not give) as null: JSON has no NaN.
nlohmann::ordered_json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr); }

nlohmann::ordered_json refinement_json(const RefineSummary& r) {
  nlohmann::ordered_json parameters = nlohmann::ordered_json::array(), records = nlohmann::ordered_json::array();
  for (const auto& q : r.parameters) {
    parameters.push_back({{"name", q.name}, {"equation_error", q.linear}, {"refined", q.refined}, {"standard_error", finite_or_null(q.standard_error)}});
    if (!q.unit.empty()) parameters.back()["unit"] = q.unit;
  }
  for (const auto& rec : r.records) {
    nlohmann::ordered_json state = nlohmann::ordered_json::object(), before = nlohmann::ordered_json::object(),
                           after = nlohmann::ordered_json::object();
    for (const auto& [name, value] : rec.initial_state) state[name] = value;
    for (const auto& [name, value] : rec.rms_before) before[name] = value;
    for (const auto& [name, value] : rec.rms_after) after[name] = value;
    records.push_back({{"path", rec.path}, {"first_sample", rec.first_sample}, {"samples", rec.samples}, {"segments", rec.segments},
                       {"initial_state", std::move(state)},
                       {"rms_error_before", std::move(before)}, {"rms_error_after", std::move(after)}});
  }
  return {{"status", to_string(r.status)}, {"message", r.message},      {"iterations", r.iterations},
          {"residuals", r.residuals},     {"unknowns", r.unknowns},    {"cost_before", r.cost_before},
          {"cost_after", r.cost_after},   {"seconds", r.seconds}, {"output_error_white", r.output_error_white},
          {"parameters", std::move(parameters)}, {"records", std::move(records)}};
}

nlohmann::ordered_json nonlinear_json(const VariableProjectionSummary& v) {
  nlohmann::ordered_json parameters = nlohmann::ordered_json::array();
  for (std::size_t k = 0; k < v.names.size(); ++k)
    parameters.push_back({{"name", v.names[k]}, {"guess", v.guesses[k]}, {"held", v.values[k]},
                          {"standard_error", k < v.standard_errors.size() ? finite_or_null(v.standard_errors[k]) : nlohmann::ordered_json(nullptr)}});
  nlohmann::ordered_json edge = nlohmann::ordered_json::array();
  for (const auto& name : v.at_edge) edge.push_back(name);
  return {{"method", "variable projection"}, {"fits", v.fits},       {"G_guess", v.G_guess},           {"G_held", v.G_best},
          {"at_edge", std::move(edge)},       {"interval_note", v.interval_note}, {"parameters", std::move(parameters)}};
}

}  // namespace

std::vector<std::string> fit_file_paths(const std::string& directory) {
  const fs::path d(directory);
  return {(d / "fit.json").string(), (d / "residuals.csv").string(), (d / "validation.csv").string(), (d / "local.csv").string()};
}

std::string select_file_path(const std::string& directory) { return (fs::path(directory) / "select.json").string(); }

nlohmann::ordered_json outliers_json(const std::vector<OutlierScan>& scans) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (const auto& scan : scans) {
    nlohmann::ordered_json samples = nlohmann::ordered_json::array();
    for (const auto& o : scan.found)
      samples.push_back({{"sample", o.sample}, {"t", o.time}, {"recorded", o.value}, {"replaced_by", o.replacement}, {"scale_multiple", o.size}});
    out.push_back({{"record", scan.record}, {"signal", scan.signal}, {"column", scan.column}, {"threshold", scan.threshold}, {"samples", std::move(samples)}});
  }
  return out;
}

nlohmann::ordered_json fit_document(const FitFiles& f) {
  auto json = fit_json(f.summary, f.compiled, f.compiled_path, f.options);
  if (f.validation) json["validation"] = validation_json(*f.validation, f.records.size());
  json["residual_analysis"] = residual_json(f.residuals);
  nlohmann::ordered_json choice;  // null unless the form was chosen from the data
  if (f.form_choice) {
    nlohmann::ordered_json forms = nlohmann::ordered_json::array();
    for (const auto& s : f.form_choice->scores)
      forms.push_back({{"form", s.name},
                       {"worst_fit_percent", s.worst_fit_percent ? nlohmann::ordered_json(*s.worst_fit_percent) : nlohmann::ordered_json(nullptr)},
                       {"better_pieces", s.better_pieces}, {"pieces", s.pieces}, {"note", s.note}});
    choice = {{"chosen", f.form_choice->scores[f.form_choice->chosen].name}, {"forms", std::move(forms)}};
  }
  json["form_choice"] = std::move(choice);
  json["refinement"] = f.refinement ? refinement_json(*f.refinement) : nlohmann::ordered_json(nullptr);
  json["instrumental_variables"] = f.instrumental_variables ? instrumental_variables_json(*f.instrumental_variables) : nlohmann::ordered_json(nullptr);
  json["noise_check"] = f.noise_check ? noise_check_json(*f.noise_check) : nlohmann::ordered_json(nullptr);
  json["outliers"] = f.outliers ? outliers_json(*f.outliers) : nlohmann::ordered_json(nullptr);
  json["local"] = f.local ? local_json(*f.local) : nlohmann::ordered_json(nullptr);
  json["nonlinear_parameters"] = f.nonlinear ? nonlinear_json(*f.nonlinear) : nlohmann::ordered_json(nullptr);
  non_finite_as_strings(json);
  return json;
}

std::variant<std::vector<std::string>, Diagnostic> write_fit_files(const std::string& directory, const FitFiles& f) {
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec) return cli_diag::cannot_create_directory(directory, ec.message());
  const auto paths = fit_file_paths(directory);
  const std::string& json_path = paths[0];
  const std::string& csv_path = paths[1];
  const std::string& validation_path = paths[2];
  const std::string& local_path = paths[3];
  const auto json = fit_document(f);
  const bool curves = f.validation && !f.validation->runs.empty();
  std::string why;
  std::optional<Diagnostic> problem;  // why the residual rows could not be had
  const ir::Model& model = f.compiled.integrated;
  // One set, renamed in together once every file is whole: a failure leaves the previous run's
  // files as they were, and a validation.csv this run does not write is removed with the commit
  // (it would read as this fit's).
  AtomicFileSet set;
  if (!set.add(json_path, json.dump(1) + "\n", &why) ||
      !set.add(csv_path, [&](std::ostream& out) { return write_residuals(out, model, f.records, f.options, f.summary, problem); }, &why) ||
      (curves && !set.add(validation_path, validation_csv(*f.validation), &why)) ||
      (f.local && !set.add(local_path, [&](std::ostream& out) { return write_local_csv(out, *f.local); }, &why)))
    return problem ? *problem : cli_diag::cannot_write(why);
  std::vector<std::string> stale;
  if (!curves) stale.push_back(validation_path);
  if (!f.local) stale.push_back(local_path);
  if (!set.commit(&why, stale)) return cli_diag::cannot_write(why);
  std::vector<std::string> written{json_path, csv_path};
  if (curves) written.push_back(validation_path);
  if (f.local) written.push_back(local_path);
  return written;
}

nlohmann::ordered_json select_json(const SelectSummary& s, const std::string& model_path, const SelectOptions& o,
                                   const std::vector<OutlierScan>* outliers) {
  using nlohmann::ordered_json;
  ordered_json j;
  j["format"] = "sidc-select";
  j["version"] = 1;
  j["sidc_version"] = SIDC_VERSION;
  j["model"] = s.model_name;
  j["model_file"] = model_path;
  j["settings"] = {{"method", to_string(o.method)}, {"folds", o.folds}, {"bootstrap", o.bootstrap}, {"seed", o.seed},
                   {"max_size", o.max_size}, {"rule", to_string(o.rule)}, {"elbow_share", o.elbow_share}, {"drift_share", o.drift_share},
                   {"keep_drift", o.keep_drift}, {"tolerance", o.tolerance},
                   {"required", o.required}, {"dropped", o.dropped}};
  ordered_json groups = ordered_json::array();
  for (const auto& g : s.groups) {
    ordered_json rows = ordered_json::array();
    for (const auto& r : g.rows) {
      ordered_json values = ordered_json::object();
      for (std::size_t k = 0; k < r.parameters.size(); ++k) values[r.parameters[k]] = r.values[k];
      rows.push_back({{"size", r.size}, {"parameters", values}, {"rank", r.rank}, {"G", r.G}, {"standard_error", r.standard_error},
                      {"elbow_left", std::isfinite(r.elbow_left) ? ordered_json(r.elbow_left) : ordered_json(nullptr)},
                      {"aic", r.aic}, {"bic", r.bic}, {"cv", std::isfinite(r.cv) ? ordered_json(r.cv) : ordered_json(nullptr)},
                      {"cv_standard_error", std::isfinite(r.cv) ? ordered_json(r.cv_standard_error) : ordered_json(nullptr)},
                      {"simulation", r.simulation ? ordered_json(*r.simulation) : ordered_json(nullptr)}});
    }
    auto size_at = [&](int index) { return index < 0 ? ordered_json(nullptr) : ordered_json(g.rows[static_cast<std::size_t>(index)].size); };
    ordered_json operations = ordered_json::object();
    for (std::size_t c = 0; c < g.columns.size(); ++c) operations[g.columns[c]] = g.operations[c];
    ordered_json frequency = ordered_json::object();
    for (std::size_t c = 0; c < g.bootstrap_frequency.size(); ++c) frequency[g.columns[c]] = g.bootstrap_frequency[c];
    ordered_json drift = ordered_json::array();
    for (const auto& d : g.drift) drift.push_back({{"column", d.column}, {"share", d.share}, {"degree", d.degree}, {"set_aside", d.set_aside}});
    std::vector<std::size_t> equations;
    for (std::size_t e : g.equations) equations.push_back(e + 1);
    groups.push_back({{"equations", equations}, {"n", g.n}, {"operations", operations}, {"required", g.required}, {"dropped", g.dropped},
                      {"method", to_string(g.method)}, {"subsets_evaluated", g.nodes}, {"subsets_total", g.subsets_total},
                      {"search_seconds", g.search_seconds}, {"path", g.path}, {"sizes", rows},
                      {"drift_absorbers", drift},
                      {"best_size", {{"elbow", size_at(g.best_elbow)}, {"aic", size_at(g.best_aic)}, {"bic", size_at(g.best_bic)}, {"cv", size_at(g.best_cv)}, {"least_cv", size_at(g.least_cv)},
                                        {"simulation", size_at(g.best_simulation)}}},
                      {"chosen_size", size_at(g.chosen)}, {"reason", g.reason}, {"non_contributory", g.non_contributory},
                      {"bootstrap", {{"replicates", g.bootstrap_replicates}, {"blocks", g.blocks}, {"frequency", frequency}}}});
  }
  j["groups"] = std::move(groups);
  j["outliers"] = outliers ? outliers_json(*outliers) : ordered_json(nullptr);
  return j;
}

std::variant<std::string, Diagnostic> write_select_file(const std::string& directory, const SelectSummary& summary, const std::string& model_path,
                                                        const SelectOptions& options, const std::vector<OutlierScan>* outliers) {
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec) return cli_diag::cannot_create_directory(directory, ec.message());
  const std::string path = select_file_path(directory);
  std::string why;
  auto json = select_json(summary, model_path, options, outliers);
  non_finite_as_strings(json);
  if (!write_file_atomically(path, json.dump(1) + "\n", &why)) return cli_diag::cannot_write(why);
  return path;
}

}  // namespace sidc
