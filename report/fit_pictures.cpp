#include "report/fit_pictures.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <set>
#include <fstream>
#include <iterator>
#include <fmt/format.h>
#include <limits>
#include <map>
#include <memory>

#include "diagnostics/cli_catalogue.hpp"
#include "report/atomic_file.hpp"
#include "ir/print.hpp"
#include "ir/queries.hpp"
#include "ir/traversal.hpp"
#include "report/fit_figures.hpp"
#include "report/gnuplot_renderer.hpp"
#include "report/html_report.hpp"
#include "runtime/operators/operator_choice.hpp"
#include "runtime/operators/plot_function.hpp"
#include "runtime/solve/fitted_values.hpp"
#include "runtime/records/records.hpp"

namespace sidc {
namespace fs = std::filesystem;

namespace {

// The values of one signal derivative over the fit window of a record, as the fit estimated them.
struct WindowValues {
  std::vector<double> time, values;
};

// One record's estimates, through one Evaluator: it keeps each derivative it has estimated, so a
// derivative drawn in several figures (a plot's range, the phase plane, the derivative errors) is
// estimated once.
class WindowEstimates {
 public:
  WindowEstimates(const SampledRecord& record, const ir::Model& model, const FitOptions& options) : record_(record) {
    // Under savgol(auto), the fit's arcs, and arcs for the first three derivatives of every
    // signal that the figures may draw beyond the model's own (phase planes, exact derivatives).
    std::vector<std::pair<std::string, int>> extra;
    for (const auto& [name, samples] : record.signals)
      for (int k = 1; k <= 3; ++k) extra.emplace_back(name, k);
    auto chosen = operators_for_record(options.evaluation, record, model, extra);
    if (!std::holds_alternative<EvaluationOptions>(chosen)) return;
    evaluation_ = std::get<EvaluationOptions>(std::move(chosen));
    auto window = fit_window(record, model, evaluation_, options.from, options.to);
    if (auto* w = std::get_if<FitWindow>(&window)) evaluator_ = std::make_unique<Evaluator>(record, model, evaluation_, *w);
  }

  // The arc of the order-th derivative of `signal`, as the figures' captions name it.
  std::string arc_of(const std::string& signal, int order) const {
    if (!evaluation_.automatic_derivative) {
      const auto& d = evaluation_.derivative;
      return fmt::format("savgol({}, {})", d.window, d.polyorder);
    }
    const auto d = derivative_options_for(evaluation_, signal, order);
    return fmt::format("savgol(auto) = savgol({}, {})", d.window, d.polyorder);
  }

  std::optional<WindowValues> of(const std::string& signal, int order) {
    if (!evaluator_) return std::nullopt;
    ir::Factor f{ir::FactorKind::signal, signal, order, {}, {}, {}, {}};
    auto all = evaluator_->evaluate(ir::factor(f));
    if (!std::holds_alternative<std::vector<double>>(all)) return std::nullopt;
    const auto& v = std::get<std::vector<double>>(all);
    const FitWindow& w = evaluator_->window();
    WindowValues out;
    for (std::size_t k = w.first; k <= w.last && k < v.size(); ++k) {
      out.time.push_back(record_.time[k]);
      out.values.push_back(v[k]);
    }
    return out;
  }

 private:
  const SampledRecord& record_;
  EvaluationOptions evaluation_;
  std::unique_ptr<Evaluator> evaluator_;  // null when the record has no fit window
};

// An exact derivative recorded in the file beside the output (`y' = "ydot"`), at the times of `at`.
std::optional<std::vector<double>> exact_column(const Record& r, const ir::DataSource& source, const std::string& column,
                                                const std::vector<double>& at) {
  std::string time_name = "t";
  for (const auto& [signal, col] : source.bindings)
    if (signal == "t") time_name = col;
  const Column* time = r.column(time_name);
  if (!time && time_name == "t") time = r.column("time");
  const Column* values = r.column(column);
  if (!time || !values || time->size() < 2) return std::nullopt;
  const double t0 = time->front(), step = ((*time)[time->size() - 1] - t0) / static_cast<double>(time->size() - 1);
  if (!(step > 0) || !std::isfinite(step)) return std::nullopt;  // no uniform time column to match by
  std::vector<double> out;
  for (double t : at) {
    const double k = std::round((t - t0) / step);
    const bool inside = std::isfinite(k) && k >= 0 && k < static_cast<double>(values->size());
    const auto i = inside ? static_cast<std::size_t>(k) : 0;
    out.push_back(inside && std::abs((*time)[i] - t) <= 1e-6 * std::max(1.0, std::abs(t)) + 1e-3 * step
                      ? (*values)[i]
                      : std::numeric_limits<double>::quiet_NaN());
  }
  return out;
}

// The highest derivative of `signal` written in the sum (guards, functions and integrals included).
int order_of(const ir::Sum& s, const std::string& signal) {
  int order = -1;
  ir::for_each_factor(s, [&](const ir::Factor& f) {
    if (f.kind == ir::FactorKind::signal && f.name == signal) order = std::max(order, f.order);
  });
  return order;
}

int order_of(const ir::Model& normalized, const std::string& signal) {
  int order = -1;
  for (const auto& e : normalized.equations) {
    order = std::max(order, order_of(e.known, signal));
    for (const auto& term : e.terms) order = std::max(order, order_of(term.operation, signal));
  }
  return order;
}

struct NamedFigure {
  Figure figure;
  int group = -1;  // the equation group it belongs to in the report; -1: the whole fit
};

// A record as titles name it: its file name (the folder is in the report's record table).
std::string record_name(const std::string& path) { return std::filesystem::path(path).filename().string(); }

std::vector<NamedFigure> fit_figures(const PictureContext& c) {
  std::vector<NamedFigure> figures;
  const ir::Model& model = c.compiled.integrated;
  const ir::Model& normalized = c.compiled.normalized;
  // Units on the axes where the model gives them (docs/language.md, "Units").
  const bool units = has_units(normalized);
  const SignalLabel time{"t", units ? to_string(time_unit(normalized)) : ""};
  auto unit_of = [&](const std::string& name) {
    const ir::Signal* s = normalized.signal(name);
    return s && s->unit ? to_string(*s->unit) : std::string();
  };
  const auto suffix = [&](std::size_t r) { return c.records.size() > 1 ? fmt::format("_r{}", r + 1) : std::string(); };

  // Figs. 4-2.5/4-2.6 and 4-2.7: the solved fitted equations against each record.
  for (std::size_t v = 0; v < c.validations.size(); ++v) {
    const ValidationSummary& run = c.validations[v];
    for (std::size_t o = 0; o < run.outputs.size(); ++o) {
      const SignalLabel output{run.outputs[o].output, unit_of(run.outputs[o].output)};
      Figure a = recorded_vs_simulated_figure(time, output, run.simulation.time.to_vector(), run.recorded[o].to_vector(), run.simulation.outputs[o]);
      Figure b = simulation_error_figure(time, output, run.simulation.time.to_vector(), run.recorded[o].to_vector(), run.simulation.outputs[o]);
      const std::string s = c.validations.size() > 1 ? fmt::format("_r{}", v + 1) : std::string();
      a.name += s, b.name += s;
      // Which record: with several, `_r2` alone does not say; a held-out one is the test on new data.
      const std::string which = v >= c.records.size() ? fmt::format(", held-out record {} (--validate, not fitted)", record_name(run.record))
                                                      : fmt::format(", record {}", record_name(run.record));
      a.title += which, b.title += which;
      figures.push_back({std::move(a)}), figures.push_back({std::move(b)});
    }
  }

  std::vector<std::unique_ptr<WindowEstimates>> per_record;
  for (const auto& record : c.records) per_record.push_back(std::make_unique<WindowEstimates>(record, model, c.options));

  // Figs. 4-1.13/4-1.14: each plotted function over the range its argument covers in the records.
  const std::vector<double> values = fitted_parameter_values(normalized, c.summary, std::numeric_limits<double>::quiet_NaN());
  for (const auto& plot : normalized.plots) {
    double low = INFINITY, high = -INFINITY;
    for (auto& estimates : per_record)
      if (auto w = estimates->of(plot.signal, plot.order))
        for (double x : w->values)
          if (std::isfinite(x)) low = std::min(low, x), high = std::max(high, x);
    if (!(low < high)) continue;
    auto curve = evaluate_plot_function(plot, values, low, high);
    if (!std::holds_alternative<PlotCurve>(curve)) continue;
    const PlotCurve& pc = std::get<PlotCurve>(curve);
    const SignalLabel argument{pc.argument, ""}, value{pc.name, ""};
    figures.push_back({reconstructed_function_figure(pc.name, argument, value, pc.x, pc.fitted,
                                                     pc.truth.empty() ? std::nullopt : std::optional(pc.truth))});
    if (!pc.truth.empty()) figures.push_back({reconstructed_function_error_figure(pc.name, argument, value, pc.x, pc.fitted, pc.truth)});
  }

  for (std::size_t r = 0; r < c.records.size(); ++r) {
    const SampledRecord& record = c.records[r];
    WindowEstimates& estimates = *per_record[r];
    // Figs. 4-1.8/4-1.9: the moving-arc estimates against the exact derivatives the file records
    // (the file is read again once: the fit kept only the columns it binds).
    if (r < c.sources.size() && !c.sources[r].exact_derivatives.empty()) {
      auto read = read_csv(c.sources[r].path);
      std::map<std::string, std::vector<DerivativeComparison>> by_signal;
      std::vector<double> at;
      for (const auto& exact : c.sources[r].exact_derivatives) {
        if (!std::holds_alternative<Record>(read)) break;
        auto w = estimates.of(exact.signal, exact.order);
        if (!w) continue;
        auto truth = exact_column(std::get<Record>(read), c.sources[r], exact.column, w->time);
        if (!truth) continue;
        at = w->time;
        by_signal[exact.signal].push_back({exact.order, w->values, *truth});
      }
      for (const auto& [signal, comparisons] : by_signal) {
        const std::string setting = fmt::format("Delta = {:g}, {}", record.step, estimates.arc_of(signal, comparisons.front().order));
        Figure f = derivative_error_figure(time, {signal, unit_of(signal)}, at, comparisons, setting);
        f.name += suffix(r);
        f.title += ", record " + record_name(record.path);
        figures.push_back({std::move(f)});
      }
    }
    // Fig. 4-1.7: the phase plane of each output of a second (or higher) order equation.
    for (const auto& s : model.signals) {
      if (s.kind != ir::Signal::Kind::output || order_of(normalized, s.name) < 2) continue;
      auto y = estimates.of(s.name, 0);
      auto y_dot = estimates.of(s.name, 1);
      if (!y || !y_dot) continue;
      Figure f = phase_plane_figure({s.name, unit_of(s.name)}, time.unit, y->values, y_dot->values);
      f.name += suffix(r);
      f.title += ", record " + record_name(record.path);
      figures.push_back({std::move(f)});
    }
  }

  // Residual analysis (MATLAB's `resid`): one autocorrelation and one cross-correlation per input.
  for (std::size_t g = 0; g < c.residuals.groups.size(); ++g) {
    const auto& rc = c.residuals.groups[g];
    if (!rc.is_usable()) continue;
    const std::string group = std::to_string(g + 1);
    figures.push_back({residual_autocorrelation_figure(rc, group), static_cast<int>(g)});
    for (std::size_t i = 0; i < rc.cross.size(); ++i)
      if (rc.cross[i].computed) figures.push_back({residual_cross_correlation_figure(rc, i, group), static_cast<int>(g)});
  }
  // Local fits: each parameter against time, per record, in its group's section.
  if (c.local) {
    const std::string what = c.local->options.forget ? fmt::format("forgetting lambda = {:g}", *c.local->options.forget)
                                                     : fmt::format("windows of {:g}", c.local->options.width);
    for (std::size_t g = 0; g < c.local->groups.size(); ++g) {
      const LocalGroupFit& group = c.local->groups[g];
      const std::size_t p = group.columns.size();
      for (std::size_t r = 0; r < group.records.size(); ++r) {
        const LocalRecordFit& fit = group.records[r];
        const std::vector<double> t(fit.t_center.begin(), fit.t_center.end());  // every parameter's abscissa
        const std::string on = c.records.size() > 1 ? what + ", " + record_name(fit.path) : what;
        for (std::size_t j = 0; j < p; ++j) {
          std::vector<double> x(fit.windows()), se(fit.windows());
          for (std::size_t k = 0; k < fit.windows(); ++k) x[k] = fit.estimates[k * p + j], se[k] = fit.standard_errors[k * p + j];
          figures.push_back({local_estimate_figure(group.columns[j], suffix(r), time, on, t, x, se), static_cast<int>(g)});
        }
      }
    }
  }
  return figures;
}

ReportContent report_content(const PictureContext& c) {
  const ir::Model& model = c.compiled.integrated;
  ReportContent content;
  content.title = fmt::format("sidc fit report: {}", model.name.empty() ? c.compiled_path : model.name);
  content.model_name = model.name;
  content.source_file = c.compiled.source->name;
  content.model_text = c.compiled.source->text;
  const auto& e = c.options.evaluation;
  content.settings = {
      {"derivatives", e.automatic_derivative
                          ? std::string("savgol(auto): a moving arc (section 3-1) per signal and derivative order, of least estimated "
                                        "mean-square error (the fit report lists each)")
                          : fmt::format("{}-point moving arc of order {} (section 3-1); second derivative {}", e.derivative.window,
                                        e.derivative.polyorder,
                                        e.derivative.second == DerivativeOptions::Second::repeated
                                            ? "by the first-derivative operator applied twice (eq. 3-1.8)"
                                            : "directly")},
      {"edges", e.derivative.edges == DerivativeOptions::Edges::drop ? "samples without a full neighbourhood dropped (the thesis)"
                                                                      : "shortened windows at the edges"},
      {"fit window", fmt::format("{} to {}", c.options.from ? fmt::format("{:g}", *c.options.from) : std::string("the record's start"),
                                 c.options.to ? fmt::format("{:g}", *c.options.to) : std::string("its end"))},
  };
  for (const auto& r : c.records) content.records.push_back(fmt::format("{} ({} samples, step {:g})", r.path, r.time.size(), r.step));
  for (std::size_t v = c.records.size(); v < c.validations.size(); ++v)
    content.records.push_back(fmt::format("{} (held out: --validate, compared with the solved equations, not fitted)", c.validations[v].record));
  for (std::size_t g = 0; g < c.summary.groups.size(); ++g) {
    const GroupFit& group = c.summary.groups[g];
    ReportGroup out;
    std::string numbers;
    for (std::size_t i : group.equations) numbers += (numbers.empty() ? "" : ", ") + std::to_string(i + 1);
    out.title = fmt::format("{} {}", group.equations.size() == 1 ? "Equation" : "Equations", numbers);
    for (std::size_t i : group.equations) out.equations.push_back(print(model.equations[i], model));
    fill_group_from(group.summary, c.options.least_squares.confidence_level, &out);
    if (g < c.residuals.groups.size())
      out.residual_verdicts.push_back(c.residuals.notes[g].empty() ? c.residuals.groups[g].verdict : c.residuals.notes[g]);
    if (c.local && g < c.local->groups.size()) out.local_fits = c.local->group_report(g);
    content.groups.push_back(std::move(out));
  }
  // The simulation covers every output at once: its table goes with the first group.
  if (!content.groups.empty()) {
    for (std::size_t v = 0; v < c.validations.size(); ++v) {
      const ValidationSummary& run = c.validations[v];
      const std::string record = v >= c.records.size() ? run.record + " (held out)" : run.record;
      for (const auto& o : run.outputs)
        content.groups.front().validation.push_back({o.output, record, o.max_abs_error, o.percent_error, o.fit_percent,
                                                     run.simulation.completed() ? std::string() : run.statement});
    }
  }
  if (!c.validation_note.empty()) content.notes.push_back("Validation by simulation " + c.validation_note);
  content.generated_by = fmt::format("sidc {}", SIDC_VERSION);
  return content;
}

// The folder holds this run's pictures only: those an earlier run listed in its manifest
// (kPictureManifest) and this run did not draw again are removed. Only names sidc wrote there, as
// the manifest lists them, plain file names ending in .svg or .png; a user's own files are never
// touched.
constexpr const char* kPictureManifest = ".sidc-pictures";

std::vector<std::string> stale_pictures(const fs::path& directory, const std::set<std::string>& now) {
  std::vector<std::string> stale;
  std::ifstream before(directory / kPictureManifest);
  for (std::string name; std::getline(before, name);) {
    const bool picture = name.ends_with(".svg") || name.ends_with(".png");
    if (picture && name.find('/') == std::string::npos && name[0] != '.' && !now.count(name)) stale.push_back((directory / name).string());
  }
  return stale;
}

// A private folder for drawing, removed with this object: gnuplot writes there, and only a whole
// set of figures leaves it, so a failure halfway leaves the user's folder as it was.
class ScratchFolder {
 public:
  ScratchFolder() {
    std::error_code ec;
    std::string pattern = (fs::temp_directory_path(ec) / "sidc-figures.XXXXXX").string();
    if (!ec && ::mkdtemp(pattern.data())) path_ = pattern;
  }
  ~ScratchFolder() {
    std::error_code ec;
    if (!path_.empty()) fs::remove_all(path_, ec);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string file_contents(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

bool write_fit_pictures(const PictureContext& context, const PictureRequest& request, std::vector<std::string>& written,
                        std::string& error) {
  if (request.plots_directory.empty() && request.report_path.empty()) return true;
  const fs::path directory = request.plots_directory;  // empty: the report's figures only
  std::error_code ec;
  if (!directory.empty()) {
    fs::create_directories(directory, ec);
    if (ec) {
      error = render(cli_diag::cannot_create_directory(directory.string(), ec.message(), "choose a folder you can write to"));
      return false;
    }
  }
  const ScratchFolder scratch;
  if (scratch.path().empty()) {
    const int why_not = errno;
    const char* tmpdir = std::getenv("TMPDIR");
    const std::string where = (tmpdir && *tmpdir ? std::string(tmpdir) : std::string("/tmp")) + "/sidc-figures.XXXXXX";
    error = render(cli_diag::cannot_create_directory(where, std::strerror(why_not), "set TMPDIR to a folder you can write to"));
    return false;
  }
  ReportContent content = report_content(context);
  std::vector<std::string> drawn;  // file names, in the scratch folder
  for (const auto& [figure, group] : fit_figures(context)) {
    const RenderSummary r = render_figure(figure, scratch.path().string(), {});
    if (!r.ok()) {
      error = render(cli_diag::cannot_draw_figure(figure.name, r.message));
      return false;
    }
    for (const auto& f : r.files) drawn.push_back(fs::path(f).filename().string());
    if (request.report_path.empty()) continue;
    std::string why;
    ReportFigure f = report_figure_from_file(r.files.front(), figure.title, &why);
    if (f.svg.empty()) {
      error = render(cli_diag::cannot_read_back_figure(figure.name, why));
      return false;
    }
    if (group >= 0 && static_cast<std::size_t>(group) < content.groups.size()) content.groups[static_cast<std::size_t>(group)].figures.push_back(std::move(f));
    else content.figures.push_back(std::move(f));
  }
  // The pictures, their manifest and the report appear together or not at all.
  AtomicFileSet set;
  std::string why;
  std::vector<std::string> stale;
  if (!directory.empty()) {
    std::set<std::string> now(drawn.begin(), drawn.end());
    std::string manifest;
    for (const auto& name : now) manifest += name + "\n";
    for (const auto& name : drawn) {
      if (!set.add((directory / name).string(), file_contents(scratch.path() / name), &why)) {
        error = render(cli_diag::cannot_write(why));
        return false;
      }
    }
    if (!set.add((directory / kPictureManifest).string(), manifest, &why)) {
      error = render(cli_diag::cannot_write(why));
      return false;
    }
    stale = stale_pictures(directory, now);
  }
  if (!request.report_path.empty() && !set.add(request.report_path, render_html_report(content), &why)) {
    error = render(cli_diag::cannot_write(why));
    return false;
  }
  if (!set.commit(&why, stale)) {
    error = render(cli_diag::cannot_write(why));
    return false;
  }
  for (const auto& name : drawn) written.push_back((directory / name).string());
  if (!request.report_path.empty()) written.push_back(request.report_path);
  return true;
}

}  // namespace sidc
