#include "report/text_reports.hpp"

#include <cmath>
#include <fmt/format.h>

namespace sidc {

std::string validation_report(const FitValidation& v) {
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

std::string residual_report(const ResidualAnalysis& analysis) {
  std::string out;
  for (std::size_t g = 0; g < analysis.groups.size(); ++g) {
    const std::string group = analysis.groups.size() > 1 ? fmt::format(" (equation group {})", g + 1) : "";
    if (!analysis.notes[g].empty()) {
      out += fmt::format("\nresidual analysis{}: {}\n", group, analysis.notes[g]);
      continue;
    }
    out += fmt::format("\n{}{}", group.empty() ? "" : fmt::format("equation group {}: ", g + 1), analysis.groups[g].brief_report());
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
