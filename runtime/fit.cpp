#include "runtime/fit.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <map>
#include <numeric>
#include <set>

#include "compiler/integrate_pass.hpp"
#include "compiler/print.hpp"
#include "grammar/diagnostic_catalogue.hpp"

namespace sidc {

namespace {

void collect_guards(const ir::Sum& s, std::map<std::string, ir::Factor>& guards) {
  for (const auto& t : s.terms)
    for (const auto& [f, power] : t.factors) {
      if (f.kind == ir::FactorKind::guard) guards.emplace(print(f), f);
      if (f.argument) collect_guards(*f.argument, guards);
    }
}

// Counts the rows of each record's window by which of the group's guards hold there.
std::variant<std::vector<Region>, Diagnostic> count_regions(const ir::Model& model, const std::vector<std::size_t>& equations,
                                                           std::vector<Evaluator>& evaluators) {
  std::map<std::string, ir::Factor> guards;
  for (std::size_t e : equations) {
    collect_guards(model.equations[e].known, guards);
    for (const auto& p : model.equations[e].terms) collect_guards(p.operation, guards);
  }
  std::vector<Region> regions;
  if (guards.empty()) return regions;
  std::map<std::string, std::size_t> counts;
  for (auto& evaluator : evaluators) {
    std::vector<std::vector<double>> values;
    for (const auto& [text, f] : guards) {
      auto v = evaluator.evaluate_in_window(ir::factor(f), "a region guard");
      if (auto* d = std::get_if<Diagnostic>(&v)) return *d;
      values.push_back(std::get<std::vector<double>>(std::move(v)));
    }
    for (std::size_t i = 0; i < evaluator.window().size(); ++i) {
      std::string key;
      std::size_t g = 0;
      for (const auto& [text, f] : guards) {
        if (values[g++][i] != 0.0) key += (key.empty() ? "" : " and ") + text;
      }
      ++counts[key.empty() ? "(no guard)" : key];
    }
  }
  for (auto& [key, n] : counts) regions.push_back({key, n});
  return regions;
}

}  // namespace

bool FitOptions::is_valid(std::string* why) const {
  if (from && to && *from > *to) {
    if (why) *why = fmt::format("the fit window starts at {} after it ends at {}", *from, *to);
    return false;
  }
  std::string reason;
  if (!evaluation.derivative.is_valid(&reason) || !evaluation.integration.is_valid(&reason) || !least_squares.is_valid(&reason)) {
    if (why) *why = reason;
    return false;
  }
  return true;
}

std::vector<std::vector<std::size_t>> equation_groups(const ir::Model& model) {
  const std::size_t n = model.equations.size();
  std::vector<std::size_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::map<int, std::size_t> owner;  // parameter -> first equation using it
  for (std::size_t e = 0; e < n; ++e)
    for (const auto& p : model.equations[e].terms) {
      auto [it, fresh] = owner.emplace(p.parameter, e);
      if (!fresh) parent[find(e)] = find(it->second);
    }
  std::map<std::size_t, std::vector<std::size_t>> groups;
  for (std::size_t e = 0; e < n; ++e) groups[find(e)].push_back(e);
  std::vector<std::vector<std::size_t>> out;
  for (auto& [root, members] : groups) out.push_back(std::move(members));
  std::sort(out.begin(), out.end());
  return out;
}

std::variant<FitSummary, Diagnostic> fit(const ir::Model& model, const std::vector<SampledRecord>& records,
                                         const FitOptions& options) {
  FitSummary summary;
  summary.model_name = model.name;
  std::vector<FitWindow> windows;
  for (const auto& r : records) {
    auto w = fit_window(r, model, options.evaluation, options.from, options.to);
    if (auto* d = std::get_if<Diagnostic>(&w)) return *d;
    windows.push_back(std::get<FitWindow>(w));
  }
  std::vector<Evaluator> evaluators;
  evaluators.reserve(records.size());
  for (std::size_t r = 0; r < records.size(); ++r) evaluators.emplace_back(records[r], model, options.evaluation, windows[r]);

  for (const auto& members : equation_groups(model)) {
    GroupFit g;
    g.equations = members;
    // Columns: each parameter once; integration constants once per record.
    std::map<std::pair<int, std::size_t>, std::size_t> column_of;  // (parameter, record or 0) -> column
    auto per_record = [&](int p) {
      return model.parameters[static_cast<std::size_t>(p)].origin == ir::Parameter::Origin::integration_constant && records.size() > 1;
    };
    std::set<int> used;
    for (std::size_t e : members)
      for (const auto& p : model.equations[e].terms) used.insert(p.parameter);
    for (int p : used) {
      const auto& parameter = model.parameters[static_cast<std::size_t>(p)];
      for (std::size_t r = 0; r < (per_record(p) ? records.size() : 1); ++r) {
        column_of[{p, per_record(p) ? r : 0}] = g.columns.size();
        g.columns.push_back(per_record(p) ? fmt::format("{}@{}", parameter.name, r + 1) : parameter.name);
      }
    }
    std::size_t total_rows = 0;
    for (std::size_t r = 0; r < records.size(); ++r) total_rows += windows[r].size() * members.size();
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(total_rows), static_cast<Eigen::Index>(g.columns.size()));
    Eigen::VectorXd b(static_cast<Eigen::Index>(total_rows));
    Eigen::VectorXd weights = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(total_rows));
    const bool weighted = std::any_of(records.begin(), records.end(), [](const SampledRecord& r) { return !r.weights.empty(); });
    std::size_t row = 0;
    for (std::size_t r = 0; r < records.size(); ++r) {
      const FitWindow& w = windows[r];
      g.records.push_back({records[r].path, records[r].time[w.first], records[r].time[w.last], records[r].step, w.first, w.size()});
      for (std::size_t e : members) {
        const ir::Equation& eq = model.equations[e];
        for (const auto& p : eq.terms) {
          const auto& parameter = model.parameters[static_cast<std::size_t>(p.parameter)];
          const std::size_t column = column_of.at({p.parameter, per_record(p.parameter) ? r : 0});
          auto values = evaluators[r].evaluate_in_window(p.operation, "the operation of `" + parameter.name + "`");
          if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
          const auto& v = std::get<std::vector<double>>(values);
          for (std::size_t i = 0; i < v.size(); ++i) A(static_cast<Eigen::Index>(row + i), static_cast<Eigen::Index>(column)) = v[i];
        }
        auto known = evaluators[r].evaluate_in_window(eq.known, "the known side");
        if (auto* d = std::get_if<Diagnostic>(&known)) return *d;
        const auto& k = std::get<std::vector<double>>(known);
        for (std::size_t i = 0; i < k.size(); ++i) {
          b(static_cast<Eigen::Index>(row + i)) = k[i];
          if (!records[r].weights.empty()) weights(static_cast<Eigen::Index>(row + i)) = records[r].weights[w.first + i];
          g.row_equation.push_back(e);
          g.row_record.push_back(r);
          g.row_time.push_back(records[r].time[w.first + i]);
          g.known.push_back(k[i]);
        }
        row += k.size();
      }
    }
    auto regions = count_regions(model, members, evaluators);
    if (auto* d = std::get_if<Diagnostic>(&regions)) return *d;
    g.regions = std::get<std::vector<Region>>(std::move(regions));
    if (total_rows < g.columns.size())
      return diag::window_too_short(records.front().path, total_rows, g.columns.size(),
                                    samples_lost_each_side(std::max(1, highest_derivative_order(model)), options.evaluation.derivative));
    g.weighted = weighted;
    g.summary = solve_least_squares(A, b, g.columns, weighted ? &weights : nullptr, options.least_squares);
    summary.groups.push_back(std::move(g));
  }
  return summary;
}

bool FitSummary::is_solution_usable() const {
  return std::all_of(groups.begin(), groups.end(), [](const GroupFit& g) { return g.summary.is_solution_usable(); });
}

std::string FitSummary::brief_report() const {
  std::string out;
  for (const auto& g : groups) out += g.summary.brief_report() + "\n";
  return out;
}

std::string FitSummary::full_report(const ir::Model& model) const {
  std::string out;
  for (std::size_t gi = 0; gi < groups.size(); ++gi) {
    const GroupFit& g = groups[gi];
    const auto& s = g.summary;
    for (std::size_t e : g.equations) {
      const auto& eq = model.equations[e];
      std::string text = print_wrapped(eq, model, 96, 4);
      for (std::size_t p = text.find('\n'); p != std::string::npos; p = text.find('\n', p + 1)) text.insert(p + 1, "  ");
      out += fmt::format("equation {}{}:\n  {}\n", e + 1,
                         eq.integrations ? fmt::format(" (integrated {} time{})", eq.integrations, eq.integrations == 1 ? "" : "s") : "",
                         text);
    }
    for (const auto& r : g.records) {
      if (is_static(model))
        out += fmt::format("  record {}: rows {} to {}, n = {} per equation\n", r.path, r.first_sample + 1, r.first_sample + r.rows, r.rows);
      else
        out += fmt::format("  record {}: t0 = {:g} to {:g}, step {:g}, n = {} per equation\n", r.path, r.t0, r.t_last, r.step, r.rows);
    }
    if (!g.regions.empty()) {
      out += "  rows by region (Table 4-1.1):\n";
      for (const auto& r : g.regions) out += fmt::format("    {:>6}  {}\n", r.rows, r.guards);
    }
    out += fmt::format("  {:<14} {:>15} {:>13}   {:>31}\n", "parameter", "estimate", "std. error",
                       fmt::format("{:g}% confidence interval", 100 * 0.95));
    for (const auto& p : s.parameters)
      out += fmt::format("  {:<14} {:>15.6g} {:>13.4g}   [{:>13.6g}, {:>13.6g}]\n", p.name, p.value, p.standard_error, p.ci_low, p.ci_high);
    if (g.weighted) out += "  residuals weighted by the record's weight column (eq. 2-1.6)\n";
    out += fmt::format("  G(a) = {:.6g} (eq. 2-1.7)   standard error sqrt(G/n) = {:.4g}   residual s.d. = {:.4g}\n", s.G,
                       s.standard_error, s.residual_sd);
    out += fmt::format("  n = {}, p = {}, rank {}   R^2 = {:.6f}   AIC = {:.4g}   BIC = {:.4g}\n", s.n, s.p, s.rank, s.r_squared, s.aic, s.bic);
    out += fmt::format("  condition {:.3g} before scaling, {:.3g} after (section 3-2); about {:.1f} digits lost\n", s.condition_before,
                       s.condition_after, s.digits_lost_estimate);
    out += fmt::format("  arithmetic: {}\n", s.arithmetic);
    // Double precision carries about 16 digits; the scaled condition number says how many survive.
    if (const double left = 16 - s.digits_lost_estimate; s.is_solution_usable() && left < 4)
      out += fmt::format("  WARNING: only about {:.0f} correct digit{} can be expected in the estimates (condition {:.3g} after scaling)\n",
                         std::max(0.0, left), left >= 0.5 && left < 1.5 ? "" : "s", s.condition_after);
    if (!s.is_solution_usable()) out += fmt::format("  NOT USABLE: {}: {}\n", to_string(s.termination), s.message);
    for (const auto& group : s.dependent_groups) {
      std::string names;
      for (const auto& n : group) names += (names.empty() ? "" : ", ") + n;
      out += "  dependent operations: " + names + "\n";
    }
    if (gi + 1 < groups.size()) out += "\n";
  }
  return out;
}

}  // namespace sidc
