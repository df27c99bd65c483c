#include "runtime/solve/residual_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sidc {
namespace {

// The widest Newey-West to classical standard error ratio over the group's parameters.
double hac_widening(const GroupFit& g) {
  double widest = std::numeric_limits<double>::quiet_NaN();
  if (!g.hac.computed) return widest;
  for (std::size_t j = 0; j < g.summary.parameters.size() && j < g.hac.standard_errors.size(); ++j) {
    const double classical = g.summary.parameters[j].standard_error, ratio = g.hac.standard_errors[j] / classical;
    if (classical > 0 && std::isfinite(ratio)) widest = std::isnan(widest) ? ratio : std::max(widest, ratio);
  }
  return widest;
}

std::vector<std::string> input_names(const ir::Model& model) {
  std::vector<std::string> names;
  for (const auto& s : model.signals)
    if (s.kind == ir::Signal::Kind::input) names.push_back(s.name);
  return names;
}

}  // namespace

ResidualAnalysis analyse_residuals(const ir::Model& model, const FitSummary& summary, const std::vector<SampledRecord>& records,
                                   const FitOptions& options) {
  ResidualAnalysis out;
  const auto inputs = input_names(model);
  for (std::size_t g = 0; g < summary.groups.size(); ++g) {
    out.hac_widening.push_back(hac_widening(summary.groups[g]));
    out.trust_newey_west.push_back(false);
    if (!summary.groups[g].subdomains.empty()) {  // weak_design.hpp
      out.groups.emplace_back();
      out.notes.push_back("not computed: the weak form's rows are overlapping subdomains, their residuals correlated by construction, "
                          "so a whiteness test says nothing about the model");
      out.truncated.push_back(false);
      continue;
    }
    const GroupResiduals segments = group_residuals(model, records, options, summary, g, inputs, kMaxResidualRows);
    out.truncated.push_back(segments.truncated);
    if (!segments.ok) {
      out.groups.emplace_back();
      out.notes.push_back("not computed: " + segments.message);
      continue;
    }
    out.groups.push_back(residual_correlation(segments.residuals, segments.inputs, {}));
    out.notes.push_back(out.groups.back().is_usable() ? std::string() : "not computed: " + out.groups.back().message);
    out.trust_newey_west.back() = summary.groups[g].hac.computed && trust_newey_west(out.groups.back(), out.hac_widening.back());
  }
  return out;
}

}  // namespace sidc
