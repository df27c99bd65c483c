#include "report/text_reports.hpp"

#include <cmath>
#include <limits>
#include <fmt/format.h>

#include "diagnostics/time_text.hpp"
#include "ir/queries.hpp"

namespace sidc {

namespace {

std::string derivative_label(const std::string& signal, int order) {
  if (signal.find('(') != std::string::npos) return fmt::format("{} (order {})", signal, order);  // a der() factor
  return order <= 3 ? signal + std::string(static_cast<std::size_t>(order), '\'') : fmt::format("{}^({})", signal, order);
}

// " rad", " rad/s^2" for a signal's derivative of `order`, or "" when the model gives no unit.
std::string unit_suffix(const ir::Model& model, const std::string& signal, int order) {
  const ir::Signal* s = model.signal(signal);
  if (!s || !s->unit) return {};
  const ir::Unit unit = ir::simplest(ir::divide(*s->unit, ir::power(time_unit(model), Number::rational(order, 1))));
  return " " + ir::to_string(unit);
}

}  // namespace

std::string operator_report(const std::vector<OperatorReport>& reports, const EvaluationOptions& options, const ir::Model& model) {
  std::string out;
  for (const auto& r : reports) {
    if (r.noise.empty() && r.arcs.empty()) continue;  // a static model: rows, not a time series
    out += fmt::format("record {}: noise levels (MAD of k-th differences) and derivative operators\n", r.record);
    for (const auto& s : r.noise) {
      const NoiseLevel& n = s.level;
      if (n.constant) out += fmt::format("  {:<10} noise 0 (constant signal)\n", s.signal);
      else
        out += fmt::format("  {:<10} noise sigma {:.3g}{} = {:.3g}% of its spread {:.4g}{} (differences of order {}){}\n", s.signal, n.sigma,
                           unit_suffix(model, s.signal, 0), 100 * n.relative(), n.spread, unit_suffix(model, s.signal, 0), n.difference_order,
                           n.exceeds_variation() ? "  WARNING: noise exceeds variation" : "");
    }
    if (!r.automatic) {
      const auto& d = options.derivative;
      out += fmt::format("  derivatives: savgol({}, {}) as set; higher orders {}\n", d.window, d.polyorder,
                         d.second == DerivativeOptions::Second::repeated ? "by the first-derivative arc repeated (eq. 3-1.8)" : "by the direct arc");
      continue;
    }
    for (const auto& a : r.arcs) {
      out += fmt::format("  {:<10} {}, estimated rms error {:.3g}{} (bias {:.3g}, noise {:.3g}){}\n", derivative_label(a.signal, a.order) + ":",
                         a.describe(), a.rms_error(), unit_suffix(model, a.signal, a.order), a.bias, a.noise,
                         a.noise_free ? "; noise 0: the smallest arc" : "");
    }
  }
  return out;
}

std::string outlier_report(const std::vector<OutlierScan>& scans, const std::string& keep_option) {
  constexpr std::size_t kListed = 10;
  std::string out;
  for (const auto& scan : scans) {
    const std::size_t n = scan.found.size();
    out += fmt::format("record {}: {} isolated sample{} of {} replaced by {} neighbours' value (outliers: off the quadratic through the\n"
                       "  3 samples either side by more than {:.3g} times the residuals' robust scale, alone, and off the line each side\n"
                       "  follows; {} keeps them)\n",
                       scan.record, n, n == 1 ? "" : "s", scan.signal, n == 1 ? "its" : "their", scan.threshold, keep_option);
    out += fmt::format("  {:>14} {:>14} {:>14} {:>12}\n", "t", "recorded", "replaced by", "|r| / scale");
    for (std::size_t k = 0; k < std::min(n, kListed); ++k) {
      const IsolatedOutlier& o = scan.found[k];
      out += fmt::format("  {:>14} {:>14.7g} {:>14.7g} {:>12.3g}\n", time_text(o.time, scan.step, 6), o.value, o.replacement, o.size);
    }
    if (n > kListed) out += fmt::format("  ... and {} more (fit.json lists every one)\n", n - kListed);
  }
  return out;
}

std::string outlier_warning(const OutlierScan& scan, const std::string& command, const std::string& keep_option) {
  const std::size_t n = scan.found.size();
  std::string times;
  for (std::size_t k = 0; k < std::min<std::size_t>(n, 5); ++k) times += (k ? ", " : "") + time_text(scan.found[k].time, scan.step, 6);
  if (n > 5) times += ", ...";
  return fmt::format("{}: warning: {}: {} isolated sample{} of `{}` replaced as outlier{} (t = {}): a single sample far off its neighbours "
                     "is a glitch of the record, not of the model; {} keeps them",
                     command, scan.record, n, n == 1 ? "" : "s", scan.signal, n == 1 ? "" : "s", times, keep_option);
}

namespace {

// "its largest value 5 in 14 runs (312 samples)" for each clipped side.
std::string clipped_sides(const Clipping& c) {
  std::string out;
  for (const auto* side : {&c.top, &c.bottom}) {
    if (!side->found) continue;
    out += fmt::format("{}its {} value {:.7g} in {} run{} of 2 or more samples ({} samples)", out.empty() ? "" : " and ",
                       side == &c.top ? "largest" : "smallest", side->value, side->runs, side->runs == 1 ? "" : "s", side->samples);
  }
  return out;
}

}  // namespace

std::string clipping_report(const std::vector<Clipping>& clipped) {
  std::string out;
  for (const auto& c : clipped)
    out += fmt::format("record {}: {} looks clipped (a sensor at the end of its range writes its rail value):\n"
                       "  it sits at {}, from t = {} to {}.\n"
                       "  There the record is not the system's output, the equations do not hold and the estimates are biased:\n"
                       "  fit a window without those samples (--from, --to; --split-at-gaps cuts them out), or model the saturation\n",
                       c.record, c.signal, clipped_sides(c), time_text(c.first_time, c.step, 6), time_text(c.last_time, c.step, 6));
  return out;
}

std::string clipping_warning(const Clipping& c, const std::string& command) {
  return fmt::format("{}: warning: {}: `{}` looks clipped: it sits at {} (t = {} to {}); the fit over those samples is biased "
                     "(--split-at-gaps cuts them out)",
                     command, c.record, c.signal, clipped_sides(c), time_text(c.first_time, c.step, 6), time_text(c.last_time, c.step, 6));
}

std::string validation_report(const FitValidation& v, std::size_t fitted_records) {
  std::string out;
  if (!v.note.empty()) out += "\nvalidation: " + v.note + "\n";
  for (std::size_t i = 0; i < v.runs.size(); ++i) {
    const auto& run = v.runs[i];
    out += "\n";
    if (i >= fitted_records) out += fmt::format("held-out record `{}` (--validate): not used in fitting, so this is a test on new data\n", run.record);
    out += run.report(v.method);
    if (run.truncated)
      out += fmt::format("  (the first {} samples only: --validate-samples N compares more, 0 all; about 16 equation evaluations a sample)\n",
                         v.max_samples);
  }
  return out;
}

std::string residual_report(const ResidualAnalysis& analysis) {
  std::string out;
  for (std::size_t g = 0; g < analysis.groups.size(); ++g) {
    const std::string group = analysis.groups.size() > 1 ? fmt::format(" (equation group {})", g + 1) : "";
    if (!analysis.notes[g].empty()) {
      out += fmt::format("\nresidual analysis{}: {}\n", group, analysis.notes[g]);
      continue;
    }
    out += fmt::format("\n{}{}", group.empty() ? "" : fmt::format("equation group {}: ", g + 1), analysis.groups[g].brief_report(g < analysis.hac_widening.size() ? analysis.hac_widening[g] : std::numeric_limits<double>::quiet_NaN()));
    if (g < analysis.truncated.size() && analysis.truncated[g])
      out += fmt::format("{}  (the first {} rows only)\n", out.back() == '\n' ? "" : "\n", kMaxResidualRows);
  }
  if (!out.empty() && out.back() != '\n') out += "\n";
  return out;
}

// The numbers and marks come from runtime/solve/model_comparison.hpp; this is their table.
std::string comparison_table(const ModelComparison& c) {
  std::string out = "\nmodel comparison (thesis Table 4-1.2; smaller is better in the last four columns):\n";
  out += fmt::format("  {:<28} {:>6} {:>4} {:>14} {:>12} {:>11} {:>11}\n", "model", "n", "p", "G(a)", "sqrt(G/n)", "AIC", "BIC");
  for (const auto& m : c.models) {
    std::string marks;
    if (m.least_G) marks += " least G";
    if (m.best_aic) marks += " best AIC";
    if (m.best_bic) marks += " best BIC";
    if (!m.usable) marks = " (rank deficient)";
    out += fmt::format("  {:<28} {:>6} {:>4} {:>14.6g} {:>12.4g} {:>11.4g} {:>11.4g}{}\n", m.name, m.n, m.p, m.G,
                       std::sqrt(m.G / static_cast<double>(m.n)), m.aic, m.bic, marks);
  }
  if (!c.same_known)
    out += "  (the models' known sides differ, as between a derivative and an integrated form, so their residuals\n"
           "   are in different units: neither G(a) nor AIC and BIC rank them; compare them by their parameters)\n";
  else if (!c.same_rows)
    out += "  (the models were fitted to different numbers of rows, so G(a) does not rank them; AIC and BIC do)\n";
  return out;
}

}  // namespace sidc
