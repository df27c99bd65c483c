// Determination of operations over time-block triangles (see select.hpp).
//
// Relies on: evaluate.hpp (Evaluator, fit_window), fit.hpp (FitOptions, equation_groups),
// design.hpp (the columns and rows), triangular_accumulator.hpp, best_subset.hpp,
// sequential_threshold.hpp, forward_regression.hpp, streamed_rows.hpp. Guarantees: the header's.
// The rows of one record are built over its fit window as the dense fit builds them, then cut into
// blocks of time and folded: p x n doubles while one record is evaluated, and O(F p^2) after. A
// record whose design exceeds FitOptions::stream_above_entries is streamed into the same blocks
// (streamed_rows.hpp), in memory that does not grow with n.
#include "runtime/operators/operator_choice.hpp"
#include "runtime/select/select.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>

#include <fmt/format.h>

#include "ir/print.hpp"
#include "runtime/select/forward_regression.hpp"
#include "runtime/select/sequential_threshold.hpp"
#include "runtime/select/streamed_rows.hpp"
#include "runtime/solve/triangular_accumulator.hpp"
#include "runtime/solve/weak_design.hpp"
#include "runtime/not_a_number.hpp"

namespace sidc {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The structure of the search on the kept columns (indices into the kept list).
struct Structure {
  std::vector<int> required;
  std::vector<std::vector<int>> groups;
  int free_units = 0;
};

// One search on a triangle: per size, the best subset found (indices into the triangle's columns).
struct SearchResult {
  std::vector<std::vector<SubsetFit>> best;
  std::vector<std::string> path;
  std::size_t nodes = 0, subsets_total = 0;
  std::string error;
};

SearchResult search(const TriangularSystem& system, const Structure& s, SelectionMethod method, int max_size, double tolerance,
                    const std::vector<std::string>& names) {
  SearchResult result;
  const auto p = static_cast<std::size_t>(system.R.cols());
  auto list = [&](const std::vector<int>& columns) {
    std::string out;
    for (int c : columns) out += (out.empty() ? "" : ", ") + names[static_cast<std::size_t>(c)];
    return out;
  };
  switch (method) {
    case SelectionMethod::automatic:
    case SelectionMethod::exact: {
      BestSubsetOptions o;
      o.required = s.required;
      o.groups = s.groups;
      o.max_size = max_size;
      o.tolerance = tolerance;
      BestSubsetSummary b = best_subsets(system, o);
      if (b.termination != BestSubsetSummary::Termination::success) result.error = b.message;
      result.best = std::move(b.best);
      result.nodes = b.nodes;
      result.subsets_total = b.subsets_total;
      break;
    }
    case SelectionMethod::stlsq: {
      SequentialThresholdOptions o;
      o.required = s.required;
      o.groups = s.groups;
      result.best = threshold_sweep(system, o);
      for (std::size_t k = 0; k < result.best.size(); ++k)
        if (max_size >= 0 && static_cast<int>(k) > max_size) result.best[k].clear();
      // The path at the default threshold, for the report.
      const SequentialThresholdSummary one = sequential_threshold(system, o);
      if (one.termination != SequentialThresholdSummary::Termination::success) result.error = one.message;
      for (std::size_t i = 0; i < one.path.size(); ++i)
        result.path.push_back(fmt::format("iteration {}: {} terms, G = {:.6g}: {}", i + 1, one.path[i].support.size(), one.path[i].G,
                                          list(one.path[i].support)));
      result.path.push_back(fmt::format("threshold {} on |a_j| ||op_j|| / ||known||; {}", o.threshold,
                                        one.converged ? "converged (support unchanged)" : "did not converge"));
      break;
    }
    case SelectionMethod::frols: {
      ForwardRegressionOptions o;
      o.required = s.required;
      o.groups = s.groups;
      o.max_terms = max_size;
      const ForwardRegressionSummary f = forward_regression(system, o);
      if (f.termination != ForwardRegressionSummary::Termination::success) result.error = f.message;
      result.best.assign(p + 1, {});
      std::vector<int> so_far;
      // Sizes below the required ones: only the empty model when nothing is required.
      if (s.required.empty()) result.best[0] = {SubsetFit{{}, f.G_empty}};
      for (std::size_t i = 0; i < f.steps.size(); ++i) {
        const auto& step = f.steps[i];
        so_far.insert(so_far.end(), step.entered.begin(), step.entered.end());
        std::vector<int> sorted = so_far;
        std::sort(sorted.begin(), sorted.end());
        result.best[sorted.size()] = {SubsetFit{sorted, step.G}};
        result.path.push_back(fmt::format("step {}: + {}{}   ERR = {:.6f}   cumulative ERR = {:.8f}   G = {:.6g}", i + 1, list(step.entered),
                                          step.required ? " (required)" : "", step.err, step.cumulative_err, step.G));
      }
      break;
    }
  }
  return result;
}

double aic_of(double G, double n, double k) { return n * std::log(G / n) + 2 * k; }
double bic_of(double G, double n, double k) { return n * std::log(G / n) + k * std::log(n); }

// The index (into rows) with the smallest value, ties to the smaller size; -1 when none is finite.
int argmin(const std::vector<SizeRow>& rows, double (*value)(const SizeRow&)) {
  int best = -1;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const double v = value(rows[i]);
    if (std::isfinite(v) && (best < 0 || v < value(rows[static_cast<std::size_t>(best)]))) best = static_cast<int>(i);
  }
  return best;
}

// The size a rule picks from per-size G on n rows (for bootstrap replicates; cv uses `cv_size`,
// the size CV chose on all rows, -1 when cross-validation is off).
int size_by_rule(const std::vector<std::vector<SubsetFit>>& best, double n, SizeRule rule, int cv_size, double elbow_share) {
  if (rule == SizeRule::cv) return cv_size;
  if (rule == SizeRule::elbow) {
    std::vector<double> G;
    std::vector<int> sizes;
    for (std::size_t k = 0; k < best.size(); ++k)
      if (!best[k].empty()) G.push_back(best[k].front().G), sizes.push_back(static_cast<int>(k));
    const ElbowResult elbow = relative_g_elbow(G, elbow_share);
    if (elbow.index < 0) return cv_size;
    const int size = sizes[static_cast<std::size_t>(elbow.index)];
    return cv_size >= 0 ? std::min(size, cv_size) : size;
  }
  int pick = -1;
  double value = INFINITY;
  for (std::size_t k = 0; k < best.size(); ++k) {
    if (best[k].empty()) continue;
    const double G = std::max(best[k].front().G, std::numeric_limits<double>::min());
    const double v = rule == SizeRule::aic ? aic_of(G, n, static_cast<double>(k)) : bic_of(G, n, static_cast<double>(k));
    if (v < value) value = v, pick = static_cast<int>(k);
  }
  return pick;
}

TriangularSystem merged(const std::vector<TriangularAccumulator>& blocks, const std::vector<std::size_t>& which, int p) {
  TriangularAccumulator total(p);
  for (std::size_t b : which) total.merge(blocks[b]);
  return total.system();
}

}  // namespace

const char* to_string(SelectionMethod method) {
  switch (method) {
    case SelectionMethod::automatic: return "automatic";
    case SelectionMethod::exact: return "exact";
    case SelectionMethod::stlsq: return "stlsq";
    case SelectionMethod::frols: return "frols";
  }
  return "?";
}

const char* to_string(SizeRule rule) {
  switch (rule) {
    case SizeRule::aic: return "AIC";
    case SizeRule::bic: return "BIC";
    case SizeRule::cv: return "CV";
    case SizeRule::elbow: return "elbow";
  }
  return "?";
}

bool SelectOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string text) {
    if (why) *why = std::move(text);
    return false;
  };
  if (!fit.is_valid(why)) return false;
  if (folds == 1 || folds < 0) return fail(fmt::format("--folds must be 0 (off) or at least 2, not {}", folds));
  if (folds > 1000) return fail(fmt::format("--folds {} is more folds than sense: at most 1000", folds));
  if (bootstrap < 0) return fail(fmt::format("--bootstrap must be >= 0, not {}", bootstrap));
  if (rule == SizeRule::cv && folds == 0) return fail("the size rule `cv` needs cross-validation: give --folds K with K >= 2");
  if (!(tolerance >= 0)) return fail("the tolerance must be >= 0");
  if (!(elbow_share > 0 && elbow_share < 1)) return fail(fmt::format("the elbow share must be between 0 and 1, not {}", elbow_share));
  if (!(drift_share > 0 && drift_share <= 1)) return fail(fmt::format("the drift share must be in (0, 1], not {}", drift_share));
  return true;
}

std::vector<std::string> selectable_parameters(const ir::Model& model) {
  std::vector<std::string> names;
  for (const auto& p : model.parameters)
    if (p.origin != ir::Parameter::Origin::integration_constant) names.push_back(p.name);
  return names;
}

std::variant<SelectSummary, Diagnostic> select_operations(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                          const SelectOptions& options) {
  SelectSummary summary;
  summary.model_name = model.name;
  summary.rule = options.rule;
  summary.folds = options.folds;
  summary.elbow_share = options.elbow_share;
  const int folds = options.folds;
  const int fine = folds >= 2 ? folds * ((10 + folds - 1) / folds) : 10;
  std::vector<FitWindow> windows;
  std::vector<EvaluationOptions> evaluation;  // per record: under savgol(auto), its own arcs, as fit chooses them
  for (const auto& r : records) {
    auto chosen = operators_for_record(options.fit.evaluation, r, model);
    if (auto* d = std::get_if<Diagnostic>(&chosen)) return *d;
    evaluation.push_back(std::get<EvaluationOptions>(std::move(chosen)));
    auto w = fit_window(r, model, evaluation.back(), options.fit.from, options.fit.to);
    if (auto* d = std::get_if<Diagnostic>(&w)) return *d;
    windows.push_back(std::get<FitWindow>(w));
  }

  for (const auto& members : equation_groups(model)) {
    const auto started = std::chrono::steady_clock::now();
    GroupSelection g;
    g.equations = members;
    // Columns and rows as fit has them (design.hpp).
    const DesignBuilder design(model, records, members);
    g.columns = design.column_names();
    g.column_parameters = design.column_indices();
    std::vector<std::string> base_name;  // the parameter's name, for `required`, `groups` and `dropped`
    std::vector<char> constant;
    for (const DesignColumn& c : design.columns()) {
      const ir::Parameter& parameter = model.parameters[c.index.parameter];
      base_name.push_back(parameter.name);
      constant.push_back(parameter.origin == ir::Parameter::Origin::integration_constant);
      std::string operation;
      for (std::size_t e : members)
        for (const auto& t : model.equations[e].terms)
          if (static_cast<std::size_t>(t.parameter) == c.index.parameter) operation += (operation.empty() ? "" : "; ") + print(t.operation);
      g.operations.push_back(operation);
    }
    const auto p = static_cast<int>(g.columns.size());
    // Drift test (size_rule.hpp): per column, the least polynomial share over the records and
    // equations where the operation occurs, and whether one of those equations is integrated.
    std::vector<double> drift_share(static_cast<std::size_t>(p), kNaN);
    std::vector<int> drift_degree(static_cast<std::size_t>(p), 0);
    std::vector<char> integrated(static_cast<std::size_t>(p), 0);

    // Rows, folded into `fine` contiguous blocks of time per record (block b of every record
    // goes to triangle b).
    std::vector<TriangularAccumulator> blocks(static_cast<std::size_t>(fine), TriangularAccumulator(p));
    auto weak = is_weak_group(model, members);
    if (auto* d = std::get_if<Diagnostic>(&weak)) return *d;
    // Per column: the least line share over the records and equations where its operation occurs.
    const auto note_shares = [&](std::size_t k, const std::vector<double>& share) {
      const int integrations = model.equations[members[k]].integrations;
      for (std::size_t c = 0; c < share.size(); ++c) {
        if (std::isnan(share[c])) continue;
        if (std::isnan(drift_share[c]) || share[c] < drift_share[c]) drift_share[c] = share[c], drift_degree[c] = integrations + 1;
        if (integrations > 0) integrated[c] = 1;
      }
    };
    for (std::size_t r = 0; r < records.size(); ++r) {
      // A design larger than the fit keeps whole is streamed, as fit streams it (streamed_rows.hpp);
      // a problem there sends the record to the whole rows below, which word it.
      if (!std::get<bool>(weak) && windows[r].size() * members.size() * static_cast<std::size_t>(p) > options.fit.stream_above_entries) {
        std::vector<std::vector<double>> shares;
        auto streamed = stream_record_rows(model, records, r, evaluation[r], windows[r], design, members, options.fit, blocks, shares);
        if (auto* d = std::get_if<Diagnostic>(&streamed)) return *d;
        if (std::get<StreamedRows>(streamed) == StreamedRows::folded) {
          for (std::size_t k = 0; k < shares.size(); ++k) note_shares(k, shares[k]);
          continue;
        }
      }
      Evaluator evaluator(records[r], model, evaluation[r], windows[r]);
      std::vector<double> expression;  // eq. 2-1.6 as sidc fit applies it
      if (model.weights) {
        auto values = expression_weights(model, evaluator);
        if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
        expression = std::get<std::vector<double>>(std::move(values));
      }
      // Rows per equation: the window's samples, or the weak form's subdomains (weak_design.hpp).
      std::size_t W = windows[r].size();
      const std::size_t E = members.size();
      Eigen::MatrixXd A;
      Eigen::VectorXd b, weights;
      if (std::get<bool>(weak)) {
        auto made = weak_record_design(model, records, r, evaluator, design, members, expression, options.fit.share);
        if (auto* d = std::get_if<Diagnostic>(&made)) return *d;
        WeakDesign& wd = std::get<WeakDesign>(made);
        W = wd.grids.front().centres.size();
        A = std::move(wd.A), b = std::move(wd.b), weights = std::move(wd.weights);
      } else {
        A = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(W * E), p);
        b.resize(static_cast<Eigen::Index>(W * E));
        weights = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(W * E));
        if (auto problem = design.window_rows(r, evaluator, expression, A, b, weights, 0)) return *problem;
        // The drift test reads sample rows; the weak form's subdomain rows do not drift.
        for (std::size_t k = 0; k < E; ++k)
          note_shares(k, operation_line_share(A.middleRows(static_cast<Eigen::Index>(k * W), static_cast<Eigen::Index>(W)),
                                              model.equations[members[k]].integrations));
      }
      const bool weighted = !records[r].weights.empty() || !expression.empty();
      for (int block = 0; block < fine; ++block) {
        const std::size_t first = W * static_cast<std::size_t>(block) / static_cast<std::size_t>(fine);
        const std::size_t last = W * static_cast<std::size_t>(block + 1) / static_cast<std::size_t>(fine);
        if (last <= first) continue;
        // The design holds equation k's row of sample i at k W + i; a block of time folds sample
        // by sample, row (i, k) at i E + k.
        const auto rows = static_cast<Eigen::Index>((last - first) * E);
        Eigen::MatrixXd Ab(rows, p);
        Eigen::VectorXd bb(rows), wb(rows);
        for (std::size_t i = first; i < last; ++i)
          for (std::size_t k = 0; k < E; ++k) {
            const auto from = static_cast<Eigen::Index>(k * W + i), to = static_cast<Eigen::Index>((i - first) * E + k);
            Ab.row(to) = A.row(from);
            bb(to) = b(from);
            wb(to) = weights(from);
          }
        std::string why;
        if (!blocks[static_cast<std::size_t>(block)].add_rows(Ab, bb, weighted ? &wb : nullptr, &why)) {
          summary.message = fmt::format("rows of `{}` could not be folded: {}", records[r].path, why);
          return summary;
        }
      }
    }
    std::vector<std::size_t> all(static_cast<std::size_t>(fine));
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    const TriangularSystem full_system = merged(blocks, all, p);
    g.n = full_system.rows;
    g.blocks = static_cast<std::size_t>(fine);
    if (auto problem = design.too_few_rows(g.n, evaluation.front())) return *problem;

    // Kept columns (not dropped, not drift absorbers set aside), required ones, groups: by name.
    auto named = [](const std::vector<std::string>& list, const std::string& name) { return std::find(list.begin(), list.end(), name) != list.end(); };
    auto grouped = [&](const std::string& name) {
      return std::any_of(options.groups.begin(), options.groups.end(), [&](const auto& group) { return named(group.second, name); });
    };
    std::vector<int> kept;
    std::vector<char> required(static_cast<std::size_t>(p), 0);
    for (int c = 0; c < p; ++c) {
      const auto u = static_cast<std::size_t>(c);
      const std::string& name = base_name[u];
      if (named(options.dropped, name)) {
        g.dropped.push_back(g.columns[u]);
        continue;
      }
      const bool is_required = constant[u] || named(options.required, name);
      if (!constant[u] && drift_share[u] >= options.drift_share) {
        // A group's member is only flagged: the group may hold the system's operations.
        const bool set_aside = integrated[u] && !is_required && !options.keep_drift && !grouped(name);
        g.drift.push_back({g.columns[u], drift_share[u], drift_degree[u], set_aside});
        if (set_aside) continue;
      }
      kept.push_back(c);
      if (is_required) required[u] = 1;
    }
    Structure structure;
    std::vector<std::string> kept_names;
    std::vector<int> index_in_kept(static_cast<std::size_t>(p), -1);
    for (std::size_t k = 0; k < kept.size(); ++k) {
      index_in_kept[static_cast<std::size_t>(kept[k])] = static_cast<int>(k);
      kept_names.push_back(g.columns[static_cast<std::size_t>(kept[k])]);
    }
    std::vector<char> in_group(kept.size(), 0);
    for (const auto& [group_name, names] : options.groups) {
      std::vector<int> unit;
      for (std::size_t k = 0; k < kept.size(); ++k)
        if (std::find(names.begin(), names.end(), base_name[static_cast<std::size_t>(kept[k])]) != names.end() && !in_group[k])
          unit.push_back(static_cast<int>(k)), in_group[k] = 1;
      if (!unit.empty()) structure.groups.push_back(unit);
    }
    // A required member requires its whole group.
    for (const auto& unit : structure.groups) {
      const bool any = std::any_of(unit.begin(), unit.end(), [&](int k) { return required[static_cast<std::size_t>(kept[static_cast<std::size_t>(k)])]; });
      if (any)
        for (int k : unit) required[static_cast<std::size_t>(kept[static_cast<std::size_t>(k)])] = 1;
    }
    int units = static_cast<int>(structure.groups.size());
    for (std::size_t k = 0; k < kept.size(); ++k) {
      if (!in_group[k]) ++units;
      if (required[static_cast<std::size_t>(kept[k])]) {
        structure.required.push_back(static_cast<int>(k));
        g.required.push_back(g.columns[static_cast<std::size_t>(kept[k])]);
      }
    }
    int required_units = 0;
    for (const auto& unit : structure.groups)
      if (required[static_cast<std::size_t>(kept[static_cast<std::size_t>(unit.front())])]) ++required_units;
    for (std::size_t k = 0; k < kept.size(); ++k)
      if (!in_group[k] && required[static_cast<std::size_t>(kept[k])]) ++required_units;
    structure.free_units = units - required_units;
    SelectionMethod method = options.method;
    if (method == SelectionMethod::automatic)
      method = structure.free_units <= kExactSearchUnitLimit && static_cast<int>(kept.size()) <= kBestSubsetMaxColumns ? SelectionMethod::exact
                                                                                                                  : SelectionMethod::frols;
    if (method == SelectionMethod::exact && static_cast<int>(kept.size()) > kBestSubsetMaxColumns) {
      summary.message = fmt::format("exact search handles at most {} candidates, not {}: use --method frols or stlsq", kBestSubsetMaxColumns,
                                    kept.size());
      return summary;
    }
    g.method = method;

    auto kept_system = [&](const TriangularSystem& s) { return restrict_columns(s, kept); };
    const TriangularSystem system = kept_system(full_system);
    const auto search_started = std::chrono::steady_clock::now();
    SearchResult found = search(system, structure, method, options.max_size, options.tolerance, kept_names);
    g.search_seconds = seconds_since(search_started);
    if (!found.error.empty()) {
      summary.message = found.error;
      return summary;
    }
    g.path = found.path;
    g.nodes = found.nodes;
    g.subsets_total = found.subsets_total;
    const double n = static_cast<double>(g.n);

    std::vector<int> size_of_row;
    for (std::size_t k = 0; k < found.best.size(); ++k) {
      if (found.best[k].empty()) continue;
      const SubsetFit& best = found.best[k].front();
      SizeRow row;
      row.size = static_cast<int>(k);
      const SubsetSolution solution = solve_subset(system, best.columns);
      for (std::size_t j = 0; j < best.columns.size(); ++j) {
        const auto c = static_cast<std::size_t>(kept[static_cast<std::size_t>(best.columns[j])]);
        row.parameters.push_back(g.columns[c]);
        row.indices.push_back(g.column_parameters[c]);
        row.values.push_back(solution.coefficients[j]);
      }
      row.rank = solution.rank;
      row.G = best.G;
      const double G = std::max(row.G, std::numeric_limits<double>::min());
      row.standard_error = std::sqrt(row.G / n);
      row.aic = aic_of(G, n, static_cast<double>(k));
      row.bic = bic_of(G, n, static_cast<double>(k));
      row.cv = kNaN;
      if (options.simulation_error) row.simulation = options.simulation_error(summary.groups.size(), row.indices, row.values);
      g.rows.push_back(std::move(row));
    }

    // K-fold cross-validation: fold f holds blocks [f c, (f+1) c), c = fine / K.
    if (folds >= 2) {
      const int per_fold = fine / folds;
      std::vector<double> test_G(static_cast<std::size_t>(kept.size()) + 1, 0.0);
      std::vector<int> counted(static_cast<std::size_t>(kept.size()) + 1, 0);
      // Per size, each fold's mean squared error per held-out row (for the standard error of CV).
      std::vector<std::vector<double>> fold_error(static_cast<std::size_t>(kept.size()) + 1);
      for (int f = 0; f < folds; ++f) {
        std::vector<std::size_t> train, test;
        for (int b = 0; b < fine; ++b) (b / per_fold == f ? test : train).push_back(static_cast<std::size_t>(b));
        const TriangularSystem training = kept_system(merged(blocks, train, p));
        const TriangularSystem held_out = kept_system(merged(blocks, test, p));
        if (held_out.rows == 0) continue;
        const SearchResult fold = search(training, structure, method, options.max_size, options.tolerance, kept_names);
        for (std::size_t k = 0; k < fold.best.size(); ++k) {
          if (fold.best[k].empty()) continue;
          const SubsetSolution solution = solve_subset(training, fold.best[k].front().columns);
          std::vector<double> x(kept.size(), 0.0);
          for (std::size_t j = 0; j < solution.coefficients.size(); ++j)
            x[static_cast<std::size_t>(fold.best[k].front().columns[j])] = solution.coefficients[j];
          const double G = G_at(held_out, x);
          test_G[k] += G;
          fold_error[k].push_back(G / static_cast<double>(held_out.rows));
          ++counted[k];
        }
      }
      for (auto& row : g.rows) {
        const auto k = static_cast<std::size_t>(row.size);
        row.cv = counted[k] == folds ? test_G[k] / n : kNaN;
        if (counted[k] == folds) {
          double mean = 0, squares = 0;
          for (double e : fold_error[k]) mean += e / folds;
          for (double e : fold_error[k]) squares += (e - mean) * (e - mean);
          row.cv_standard_error = std::sqrt(squares / (folds - 1) / folds);
        }
      }
    }
    g.best_aic = argmin(g.rows, [](const SizeRow& r) { return r.aic; });
    g.best_bic = argmin(g.rows, [](const SizeRow& r) { return r.bic; });
    g.least_cv = argmin(g.rows, [](const SizeRow& r) { return r.cv; });
    // The one-standard-error rule (Breiman et al. 1984; Hastie, Tibshirani & Friedman, sec. 7.10):
    // the smallest size whose CV is within one standard error of the least CV.
    if (g.least_cv >= 0) {
      const SizeRow& least = g.rows[static_cast<std::size_t>(g.least_cv)];
      for (std::size_t i = 0; i < g.rows.size() && g.best_cv < 0; ++i)
        if (g.rows[i].cv <= least.cv + least.cv_standard_error) g.best_cv = static_cast<int>(i);
    }
    g.best_simulation = argmin(g.rows, [](const SizeRow& r) { return r.simulation.value_or(kNaN); });
    {
      std::vector<double> G;
      for (const auto& row : g.rows) G.push_back(row.G);
      const ElbowResult elbow = relative_g_elbow(G, options.elbow_share);
      for (std::size_t i = 0; i < g.rows.size(); ++i) g.rows[i].elbow_left = elbow.left[i];
      g.best_elbow = elbow.index;
    }
    auto size_at = [&](int index) { return g.rows[static_cast<std::size_t>(index)].size; };
    switch (options.rule) {
      case SizeRule::aic:
        g.chosen = g.best_aic;
        if (g.chosen >= 0) g.reason = fmt::format("the least AIC ({:.4f})", g.rows[static_cast<std::size_t>(g.chosen)].aic);
        break;
      case SizeRule::bic:
        g.chosen = g.best_bic;
        if (g.chosen >= 0) g.reason = fmt::format("the least BIC ({:.4f})", g.rows[static_cast<std::size_t>(g.chosen)].bic);
        break;
      case SizeRule::cv:
        g.chosen = g.best_cv;
        if (g.chosen >= 0)
          g.reason = fmt::format("the smallest size whose CV is within one standard error of the least CV (k = {})", size_at(g.least_cv));
        break;
      case SizeRule::elbow: {
        g.chosen = g.best_elbow;
        if (g.chosen < 0) {
          g.chosen = g.best_cv;
          break;
        }
        const SizeRow& at = g.rows[static_cast<std::size_t>(g.chosen)];
        const std::string elbow_words =
            g.rows.size() == 1 ? fmt::format("the elbow is k = {}, the only size", at.size)
            : g.chosen + 1 == static_cast<int>(g.rows.size())
                ? fmt::format("no step before the largest size leaves at most {:.3g}% of log(G/G_full): the elbow is k = {}",
                              100 * options.elbow_share, at.size)
                : fmt::format("the step from k = {} to k = {} leaves {:.3g}% of log(G/G_full), at most {:.3g}%: the elbow is k = {}",
                              size_at(g.chosen - 1), at.size, 100 * at.elbow_left, 100 * options.elbow_share, at.size);
        if (g.best_cv >= 0 && g.best_cv < g.chosen) {
          g.reason = fmt::format("{}; CV's choice, k = {}, is smaller and is taken", elbow_words, size_at(g.best_cv));
          g.chosen = g.best_cv;
        } else if (g.best_cv >= 0) {
          g.reason = fmt::format("{}; CV's choice, k = {}, is not smaller", elbow_words, size_at(g.best_cv));
        } else {
          g.reason = elbow_words;
        }
        break;
      }
    }
    if (g.chosen >= 0) {
      const auto& chosen = g.rows[static_cast<std::size_t>(g.chosen)].indices;
      for (int c : kept)
        if (std::find(chosen.begin(), chosen.end(), g.column_parameters[static_cast<std::size_t>(c)]) == chosen.end())
          g.non_contributory.push_back(g.columns[static_cast<std::size_t>(c)]);
    }

    // Bootstrap over time blocks.
    if (options.bootstrap > 0 && g.chosen >= 0) {
      std::mt19937_64 generator(options.seed + summary.groups.size());
      std::uniform_int_distribution<std::size_t> pick(0, static_cast<std::size_t>(fine) - 1);
      std::vector<int> count(static_cast<std::size_t>(p), 0);
      const int cv_size = g.best_cv >= 0 ? g.rows[static_cast<std::size_t>(g.best_cv)].size : -1;
      for (int replicate = 0; replicate < options.bootstrap; ++replicate) {
        std::vector<std::size_t> drawn(static_cast<std::size_t>(fine));
        for (auto& d : drawn) d = pick(generator);
        const TriangularSystem resampled = kept_system(merged(blocks, drawn, p));
        const SearchResult r = search(resampled, structure, method, options.max_size, options.tolerance, kept_names);
        const int k = size_by_rule(r.best, static_cast<double>(resampled.rows), options.rule, cv_size, options.elbow_share);
        if (k < 0 || static_cast<std::size_t>(k) >= r.best.size() || r.best[static_cast<std::size_t>(k)].empty()) continue;
        for (int c : r.best[static_cast<std::size_t>(k)].front().columns) ++count[static_cast<std::size_t>(kept[static_cast<std::size_t>(c)])];
        ++g.bootstrap_replicates;
      }
      g.bootstrap_frequency.assign(static_cast<std::size_t>(p), 0.0);
      for (int c = 0; c < p; ++c)
        if (g.bootstrap_replicates > 0)
          g.bootstrap_frequency[static_cast<std::size_t>(c)] = static_cast<double>(count[static_cast<std::size_t>(c)]) / g.bootstrap_replicates;
    }
    g.total_seconds = seconds_since(started);
    summary.groups.push_back(std::move(g));
  }
  return summary;
}

std::string SelectSummary::report() const {
  std::string out;
  for (std::size_t gi = 0; gi < groups.size(); ++gi) {
    const GroupSelection& g = groups[gi];
    std::string equations;
    for (std::size_t e : g.equations) equations += (equations.empty() ? "" : ", ") + std::to_string(e + 1);
    out += fmt::format("equation{} {}: n = {} rows, {} candidate operations", g.equations.size() > 1 ? "s" : "", equations, g.n,
                       g.columns.size() - g.dropped.size());
    if (!g.required.empty()) {
      std::string names;
      for (const auto& r : g.required) names += (names.empty() ? "" : ", ") + r;
      out += " (required: " + names + ")";
    }
    out += "\n";
    if (!g.dropped.empty()) {
      std::string names;
      for (const auto& r : g.dropped) names += (names.empty() ? "" : ", ") + r;
      out += "  dropped before the search: " + names + "\n";
    }
    for (const DriftAbsorber& d : g.drift)
      out += fmt::format("  warning: `{}` is nearly a polynomial in t of degree {} over the window (before integration, a + b t holds {:.4f}% of it):\n"
                         "  a drift absorber, {}\n",
                         d.column, d.degree, 100 * d.share,
                         d.set_aside ? "set aside before the search (its coefficient would measure the integrated form's drift; --keep-drift or --require keeps it)"
                                     : "kept in the search");
    out += "  operations:\n";
    for (std::size_t c = 0; c < g.columns.size(); ++c) out += fmt::format("    {:<10} {}\n", g.columns[c], g.operations[c]);
    if (g.method == SelectionMethod::exact)
      out += fmt::format("  method: exact best subset (branch and bound over the triangle): {} of {} subsets evaluated, {:.3g} s\n", g.nodes,
                         g.subsets_total, g.search_seconds);
    else
      out += fmt::format("  method: {} ({:.3g} s); the best per size is the best this heuristic found, not necessarily the minimum\n",
                         g.method == SelectionMethod::stlsq ? "sequentially thresholded least squares (STLSQ), threshold sweep"
                                                            : "forward orthogonal regression with the error reduction ratio (FROLS)",
                         g.search_seconds);
    for (const auto& line : g.path) out += "    " + line + "\n";
    const bool has_cv = folds >= 2, has_sim = std::any_of(g.rows.begin(), g.rows.end(), [](const SizeRow& r) { return r.simulation.has_value(); });
    out += fmt::format("  {:>3}  {:<44} {:>5} {:>13} {:>10} {:>9} {:>10} {:>10}", "k", "operations of the best subset (thesis Table 4-1.2)", "n",
                       "G(a)", "std. err", "left", "AIC", "BIC");
    if (has_cv) out += fmt::format(" {:>11}", fmt::format("CV({})", folds));
    if (has_sim) out += fmt::format(" {:>11}", "sim");
    out += "\n";
    for (std::size_t i = 0; i < g.rows.size(); ++i) {
      const SizeRow& r = g.rows[i];
      std::string names;
      for (const auto& name : r.parameters) names += (names.empty() ? "" : " ") + name;
      if (names.empty()) names = "(none)";
      // Wrap long subsets: the table's operations column is 44 wide.
      std::vector<std::string> lines{""};
      for (std::size_t start = 0; start < names.size();) {
        std::size_t end = std::min(names.size(), start + 44);
        if (end < names.size()) {
          const std::size_t space = names.rfind(' ', end);
          if (space != std::string::npos && space > start) end = space;
        }
        if (!lines.back().empty()) lines.push_back("");
        lines.back() = names.substr(start, end - start);
        start = end + (end < names.size() && names[end] == ' ' ? 1 : 0);
      }
      std::string marks;
      if (static_cast<int>(i) == g.best_elbow) marks += " <elbow";
      if (static_cast<int>(i) == g.best_aic) marks += " <AIC";
      if (static_cast<int>(i) == g.best_bic) marks += " <BIC";
      if (static_cast<int>(i) == g.best_cv) marks += " <CV";
      if (static_cast<int>(i) == g.least_cv && g.least_cv != g.best_cv) marks += " (least CV)";
      if (static_cast<int>(i) == g.best_simulation) marks += " <sim";
      if (r.rank < r.size) marks += fmt::format(" (rank {})", r.rank);
      out += fmt::format("  {:>3}  {:<44} {:>5} {:>13.6g} {:>10.4g} {:>9} {:>10.4f} {:>10.4f}", r.size, lines.front(), g.n, r.G, r.standard_error,
                         std::isfinite(r.elbow_left) ? fmt::format("{:.3g}", r.elbow_left) : std::string("-"), r.aic, r.bic);
      if (has_cv) out += std::isfinite(r.cv) ? fmt::format(" {:>11.5g}", r.cv) : fmt::format(" {:>11}", "-");
      if (has_sim) out += r.simulation ? fmt::format(" {:>11.5g}", *r.simulation) : fmt::format(" {:>11}", "-");
      out += marks + "\n";
      for (std::size_t l = 1; l < lines.size(); ++l) out += fmt::format("  {:>3}  {}\n", "", lines[l]);
    }
    out += fmt::format("  left: the share of log(G/G_full) that remains after the step to this size (G_full: every candidate in);\n"
                       "  <elbow marks the first step that leaves at most {:.3g}\n", elbow_share);
    if (has_cv)
      out += fmt::format("  CV({}): mean squared error per row of held-out contiguous time blocks ({} folds); <CV marks the smallest size\n"
                         "  within one standard error of the least CV\n", folds, folds);
    if (g.chosen >= 0) {
      const SizeRow& r = g.rows[static_cast<std::size_t>(g.chosen)];
      out += fmt::format("  chosen by {}: k = {}\n", to_string(rule), r.size);
      if (!g.reason.empty()) out += "  why: " + g.reason + "\n";
      for (std::size_t j = 0; j < r.parameters.size(); ++j) out += fmt::format("    {:<10} = {:>15.7g}\n", r.parameters[j], r.values[j]);
      std::string names;
      for (const auto& c : g.non_contributory) names += (names.empty() ? "" : ", ") + c;
      out += "  non-contributory operations (section 2-3): " + (names.empty() ? std::string("none") : names) + "\n";
    }
    if (g.bootstrap_replicates > 0) {
      out += fmt::format("  bootstrap: {} replicates of {} time blocks drawn with replacement, size by {}; share of replicates selecting:\n",
                         g.bootstrap_replicates, g.blocks, to_string(rule));
      std::string line;
      for (std::size_t c = 0; c < g.columns.size(); ++c) {
        if (std::find(g.dropped.begin(), g.dropped.end(), g.columns[c]) != g.dropped.end()) continue;
        const std::string item = fmt::format("{} {:.0f}%", g.columns[c], 100 * g.bootstrap_frequency[c]);
        if (line.size() + item.size() > 90) out += "    " + line + "\n", line.clear();
        line += (line.empty() ? "" : ", ") + item;
      }
      if (!line.empty()) out += "    " + line + "\n";
    }
    if (gi + 1 < groups.size()) out += "\n";
  }
  return out;
}

}  // namespace sidc
