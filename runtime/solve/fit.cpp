#include "runtime/solve/fit.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <chrono>
#include <map>
#include <numeric>
#include <set>
#include <thread>

#include <time.h>

#include "ir/queries.hpp"
#include "ir/print.hpp"
#include "diagnostics/data_catalogue.hpp"
#include "runtime/operators/block_evaluator.hpp"
#include "runtime/solve/triangular_accumulator.hpp"

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

// The design's columns: each parameter once; integration constants once per record.
struct GroupLayout {
  std::vector<std::string> columns;
  std::map<std::pair<int, std::size_t>, std::size_t> column_of;  // (parameter, record or 0) -> column
  bool several_records = false;
  const ir::Model* model = nullptr;
  bool per_record(int p) const {
    return model->parameters[static_cast<std::size_t>(p)].origin == ir::Parameter::Origin::integration_constant && several_records;
  }
  std::size_t column(int p, std::size_t record) const { return column_of.at({p, per_record(p) ? record : 0}); }
};

GroupLayout layout_of(const ir::Model& model, const std::vector<std::size_t>& members, std::size_t record_count) {
  GroupLayout g;
  g.model = &model;
  g.several_records = record_count > 1;
  std::set<int> used;
  for (std::size_t e : members)
    for (const auto& p : model.equations[e].terms) used.insert(p.parameter);
  for (int p : used) {
    const auto& parameter = model.parameters[static_cast<std::size_t>(p)];
    for (std::size_t r = 0; r < (g.per_record(p) ? record_count : 1); ++r) {
      g.column_of[{p, g.per_record(p) ? r : 0}] = g.columns.size();
      g.columns.push_back(g.per_record(p) ? fmt::format("{}@{}", parameter.name, r + 1) : parameter.name);
    }
  }
  return g;
}

// eq. 2-1.6 with `set weights = <expression>`: every row's weight must be a finite number >= 0.
std::optional<Diagnostic> invalid_weight(const ir::Model& model, const SampledRecord& record, std::span<const double> values,
                                         std::size_t first_sample) {
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i]) || values[i] < 0)
      return diag::weight_not_valid(model.weights->span, print(model.weights->value), values[i], record.time[first_sample + i], record.path);
  return std::nullopt;
}

// What the streamed path needs besides the model and the records, shared read-only by its threads.
struct StreamPlan {
  const ir::Model& model;
  const std::vector<SampledRecord>& records;
  const std::vector<FitWindow>& windows;
  const FitOptions& options;
  const GroupLayout& layout;
  std::vector<WholeWindowValues> whole;  // per record
  std::vector<std::string> guard_texts;  // the group's guards, in count_regions' order
  std::vector<ir::Sum> guard_sums;
};

// Where the first problem lies in the dense path's order of evaluation: operation (the known side
// after the operations), term, sample + 1 (0: a problem that is not a value, found on evaluating).
using ProblemKey = std::tuple<std::size_t, std::size_t, std::size_t>;

struct StreamWorker {
  explicit StreamWorker(int p) : accumulator(p) {}
  TriangularAccumulator accumulator;
  std::map<std::string, std::size_t> region_rows;  // by a '0'/'1' string, one character per guard
  std::optional<std::pair<ProblemKey, Diagnostic>> problem, guard_problem;
  double evaluate_seconds = 0, fold_seconds = 0;

  void note(std::optional<std::pair<ProblemKey, Diagnostic>>& slot, ProblemKey key, Diagnostic d) {
    if (!slot || key < slot->first) slot.emplace(key, std::move(d));
  }
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// CPU time of the calling thread: what evaluation and folding cost, whatever else runs on the machine.
double thread_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// Window rows [begin, end) of record r for equation e, block by block: evaluated into the
// accumulator's own work area, checked, counted by region when asked, and folded.
void stream_rows(const StreamPlan& plan, StreamWorker& worker, std::size_t r, std::size_t e, std::size_t begin, std::size_t end,
                 bool count_regions) {
  const SampledRecord& record = plan.records[r];
  const FitWindow& w = plan.windows[r];
  const ir::Equation& eq = plan.model.equations[e];
  const auto p = static_cast<Eigen::Index>(plan.layout.columns.size());
  BlockEvaluator evaluator(record, plan.options.evaluation, w, plan.whole[r]);
  const std::size_t block_rows = std::max<std::size_t>(plan.options.stream_block_rows, 1);
  std::vector<double> guard_values(count_regions ? plan.guard_sums.size() * block_rows : 0);
  std::string key(plan.guard_sums.size(), '0');
  std::vector<double> weight_values(plan.model.weights ? block_rows : 0);
  for (std::size_t start = begin; start < end; start += block_rows) {
    const double clock = thread_cpu_seconds();
    const std::size_t m = std::min(block_rows, end - start);
    const std::size_t first = w.first + start;
    evaluator.start_block(first, first + m);
    auto area = worker.accumulator.rows_area(static_cast<Eigen::Index>(m));
    area.setZero();
    bool ok = true;
    const auto evaluate = [&](const ir::Sum& sum, std::span<double> out, std::size_t index, const std::string& what,
                              std::optional<std::pair<ProblemKey, Diagnostic>>& slot) {
      std::optional<NonFiniteValue> bad;
      auto status = evaluator.evaluate(sum, out, &bad);
      if (auto* d = std::get_if<Diagnostic>(&status)) {
        worker.note(slot, {index, 0, 0}, std::move(*d));
        ok = false;
      } else if (bad) {
        const ir::Term& t = sum.terms[bad->term];
        const ir::Sum single = ir::canonical(std::vector<ir::Term>{t});
        worker.note(slot, {index, bad->term, bad->sample - w.first + 1},
                    diag::operation_not_finite(t.span, print(single), what, record.time[bad->sample], record.path));
        ok = false;
      }
    };
    for (std::size_t k = 0; k < eq.terms.size(); ++k) {
      const auto& term = eq.terms[k];
      const auto column = static_cast<Eigen::Index>(plan.layout.column(term.parameter, r));
      const auto& name = plan.model.parameters[static_cast<std::size_t>(term.parameter)].name;
      evaluate(term.operation, std::span<double>(area.col(column).data(), m), k, "the operation of `" + name + "`", worker.problem);
    }
    evaluate(eq.known, std::span<double>(area.col(p).data(), m), eq.terms.size(), "the known side", worker.problem);
    if (count_regions && !plan.guard_sums.empty()) {
      for (std::size_t g = 0; g < plan.guard_sums.size(); ++g)
        evaluate(plan.guard_sums[g], std::span<double>(guard_values.data() + g * block_rows, m), r * plan.guard_sums.size() + g,
                 "a region guard", worker.guard_problem);
      for (std::size_t i = 0; i < m; ++i) {
        for (std::size_t g = 0; g < plan.guard_sums.size(); ++g) key[g] = guard_values[g * block_rows + i] != 0.0 ? '1' : '0';
        ++worker.region_rows[key];
      }
    }
    const double evaluated = thread_cpu_seconds();
    worker.evaluate_seconds += evaluated - clock;
    if (!ok || worker.problem || worker.guard_problem) continue;  // the fit ends in a diagnostic: fold nothing more
    const double* weights = record.weights.empty() ? nullptr : record.weights.data() + first;
    if (plan.model.weights) {  // checked before streaming (stream_group), so only multiplied here
      auto status = evaluator.evaluate(plan.model.weights->value, std::span<double>(weight_values.data(), m));
      if (auto* d = std::get_if<Diagnostic>(&status)) {  // not after stream_group's check, but never drop rows silently
        worker.note(worker.problem, {0, 0, 0}, std::move(*d));
        continue;
      }
      if (weights)
        for (std::size_t i = 0; i < m; ++i) weight_values[i] *= weights[i];
      weights = weight_values.data();
    }
    // A rejected block (not finite, negative weight) cannot pass the checks above; if one did, the
    // accumulator counts it and solve() says invalid_input.
    worker.accumulator.fold_rows_area(static_cast<Eigen::Index>(m), weights);
    worker.fold_seconds += thread_cpu_seconds() - evaluated;
  }
}

int stream_thread_count(const FitOptions& options) {
  if (options.stream_threads > 0) return options.stream_threads;
  return static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 8u));
}

// The streamed path for one group (FitOptions::stream_above_entries).
std::optional<Diagnostic> stream_group(const ir::Model& model, const std::vector<SampledRecord>& records,
                                       const std::vector<FitWindow>& windows, const FitOptions& options,
                                       const GroupLayout& layout, std::size_t total_rows, GroupFit& g) {
  StreamPlan plan{model, records, windows, options, layout, {}, {}, {}};
  std::map<std::string, ir::Factor> guards;
  for (std::size_t e : g.equations) {
    collect_guards(model.equations[e].known, guards);
    for (const auto& p : model.equations[e].terms) collect_guards(p.operation, guards);
  }
  for (const auto& [text, f] : guards) {
    plan.guard_texts.push_back(text);
    plan.guard_sums.push_back(ir::factor(f));
  }
  std::vector<const ir::Sum*> sums;
  for (std::size_t e : g.equations) {
    for (const auto& p : model.equations[e].terms) sums.push_back(&p.operation);
    sums.push_back(&model.equations[e].known);
  }
  for (const auto& s : plan.guard_sums) sums.push_back(&s);
  if (model.weights) sums.push_back(&model.weights->value);
  for (std::size_t r = 0; r < records.size(); ++r) {
    auto whole = prepare_whole_window_values(records[r], model, options.evaluation, windows[r], sums);
    if (auto* d = std::get_if<Diagnostic>(&whole)) return *d;
    plan.whole.push_back(std::get<WholeWindowValues>(std::move(whole)));
  }

  // Weights from an expression: every row's checked first, record by record, as the dense path does.
  if (model.weights) {
    const std::size_t block_rows = std::max<std::size_t>(options.stream_block_rows, 1);
    std::vector<double> values(block_rows);
    for (std::size_t r = 0; r < records.size(); ++r) {
      BlockEvaluator evaluator(records[r], options.evaluation, windows[r], plan.whole[r]);
      for (std::size_t start = 0; start < windows[r].size(); start += block_rows) {
        const std::size_t m = std::min(block_rows, windows[r].size() - start), first = windows[r].first + start;
        evaluator.start_block(first, first + m);
        auto status = evaluator.evaluate(model.weights->value, std::span<double>(values.data(), m));
        if (auto* d = std::get_if<Diagnostic>(&status)) return *d;
        if (auto problem = invalid_weight(model, records[r], std::span<const double>(values.data(), m), first)) return *problem;
      }
    }
  }

  const int threads = stream_thread_count(options);
  const int p = static_cast<int>(layout.columns.size());
  std::vector<StreamWorker> workers;
  for (int k = 0; k < threads; ++k) workers.emplace_back(p);
  const std::size_t block_rows = std::max<std::size_t>(options.stream_block_rows, 1);
  int threads_used = 1;
  for (std::size_t r = 0; r < records.size(); ++r) {
    for (std::size_t e : g.equations) {
      const std::size_t n = windows[r].size();
      // Contiguous parts of whole blocks, one per thread; a short window stays on one thread.
      const std::size_t blocks = (n + block_rows - 1) / block_rows;
      const std::size_t parts = std::min<std::size_t>(static_cast<std::size_t>(threads), std::max<std::size_t>(blocks / 4, 1));
      threads_used = std::max(threads_used, static_cast<int>(parts));
      const bool count = e == g.equations.front();
      std::vector<std::thread> running;
      for (std::size_t k = 1; k < parts; ++k) {
        const std::size_t begin = std::min(n, blocks * k / parts * block_rows), end = std::min(n, blocks * (k + 1) / parts * block_rows);
        running.emplace_back([&, k, begin, end, r, e] { stream_rows(plan, workers[k], r, e, begin, end, count); });
      }
      stream_rows(plan, workers[0], r, e, 0, std::min(n, blocks / parts * block_rows), count);
      for (auto& t : running) t.join();
      // The dense path's first problem: the smallest key over the parts of this record and equation.
      std::optional<std::pair<ProblemKey, Diagnostic>> first;
      for (auto& w : workers)
        if (w.problem && (!first || w.problem->first < first->first)) first = w.problem;
      if (first) return first->second;
    }
  }
  // count_regions runs after the whole design: a guard's problem only after every operation of
  // every record, ranked by record, guard and row as count_regions meets them.
  {
    std::optional<std::pair<ProblemKey, Diagnostic>> first;
    for (auto& w : workers)
      if (w.guard_problem && (!first || w.guard_problem->first < first->first)) first = w.guard_problem;
    if (first) return first->second;
  }
  std::map<std::string, std::size_t> counts;
  for (auto& w : workers)
    for (const auto& [mask, rows] : w.region_rows) {
      std::string text;
      for (std::size_t k = 0; k < mask.size(); ++k)
        if (mask[k] == '1') text += (text.empty() ? "" : " and ") + plan.guard_texts[k];
      counts[text.empty() ? "(no guard)" : text] += rows;
    }
  for (auto& [text, rows] : counts) g.regions.push_back({text, rows});
  if (total_rows < layout.columns.size())
    return diag::window_too_short(records.front().path, total_rows, layout.columns.size(),
                                  samples_lost_each_side(std::max(1, highest_derivative_order(model)), options.evaluation.derivative));

  for (std::size_t k = 1; k < workers.size(); ++k) workers[0].accumulator.merge(workers[k].accumulator);
  const auto clock = std::chrono::steady_clock::now();
  g.summary = workers[0].accumulator.solve(layout.columns, options.least_squares);
  g.solve_seconds = seconds_since(clock);
  for (const auto& w : workers) {
    g.evaluate_seconds += w.evaluate_seconds;
    g.fold_seconds += w.fold_seconds;
  }
  g.streamed = fmt::format("streamed QR over {} rows in blocks of {} rows on {} thread{}", total_rows, block_rows, threads_used,
                           threads_used == 1 ? "" : "s");
  return std::nullopt;
}

}  // namespace

// The row weights of one record from the expression, on its fit window, checked.
std::variant<std::vector<double>, Diagnostic> expression_weights(const ir::Model& model, Evaluator& evaluator) {
  auto values = evaluator.evaluate(model.weights->value);
  if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
  const auto& v = std::get<std::vector<double>>(values);
  const FitWindow& w = evaluator.window();
  std::vector<double> window(v.begin() + static_cast<std::ptrdiff_t>(w.first), v.begin() + static_cast<std::ptrdiff_t>(w.first + w.size()));
  if (auto problem = invalid_weight(model, evaluator.record(), window, w.first)) return *problem;
  return window;
}

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
    const GroupLayout layout = layout_of(model, members, records.size());
    g.columns = layout.columns;
    const auto& column_of = layout.column_of;
    const auto per_record = [&](int p) { return layout.per_record(p); };
    std::size_t total_rows = 0;
    for (std::size_t r = 0; r < records.size(); ++r) total_rows += windows[r].size() * members.size();
    g.weighted = model.weights || std::any_of(records.begin(), records.end(), [](const SampledRecord& r) { return !r.weights.empty(); });
    if (total_rows * g.columns.size() > options.stream_above_entries) {
      for (std::size_t r = 0; r < records.size(); ++r) {
        const FitWindow& w = windows[r];
        g.records.push_back({records[r].path, records[r].time[w.first], records[r].time[w.last], records[r].step, w.first, w.size()});
      }
      if (auto problem = stream_group(model, records, windows, options, layout, total_rows, g)) return *problem;
      summary.groups.push_back(std::move(g));
      continue;
    }
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(total_rows), static_cast<Eigen::Index>(g.columns.size()));
    Eigen::VectorXd b(static_cast<Eigen::Index>(total_rows));
    Eigen::VectorXd weights = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(total_rows));
    const bool weighted = g.weighted;
    std::vector<std::vector<double>> weights_of_expression(model.weights ? records.size() : 0);  // per record, on its window
    for (std::size_t r = 0; r < weights_of_expression.size(); ++r) {
      auto values = expression_weights(model, evaluators[r]);
      if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
      weights_of_expression[r] = std::get<std::vector<double>>(std::move(values));
    }
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
          if (model.weights) weights(static_cast<Eigen::Index>(row + i)) *= weights_of_expression[r][i];
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
    g.summary = solve_least_squares(A, b, g.columns, weighted ? &weights : nullptr, options.least_squares);
    summary.groups.push_back(std::move(g));
  }
  return summary;
}

std::optional<Diagnostic> for_each_residual_block(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                  const FitOptions& options, const FitSummary& summary, std::size_t group,
                                                  const std::function<bool(std::span<const ResidualRow>)>& rows, std::size_t max_rows) {
  if (group >= summary.groups.size()) return std::nullopt;
  const GroupFit& g = summary.groups[group];
  std::vector<ResidualRow> block;
  if (g.streamed.empty()) {  // dense: the rows are in the summary
    constexpr std::size_t kBlock = 4096;
    for (std::size_t start = 0; start < g.row_time.size(); start += kBlock) {
      block.clear();
      for (std::size_t i = start; i < std::min(g.row_time.size(), start + kBlock); ++i) {
        const double r = i < g.summary.residuals.size() ? g.summary.residuals[i] : std::numeric_limits<double>::quiet_NaN();
        block.push_back({g.row_equation[i], g.row_record[i], g.row_time[i], g.known[i], r});
      }
      if (!rows(block)) return std::nullopt;
    }
    return std::nullopt;
  }
  // Streamed: evaluate every block again, as stream_rows did, and apply the estimates.
  const GroupLayout layout = layout_of(model, g.equations, records.size());
  const auto p = static_cast<Eigen::Index>(layout.columns.size());
  const std::size_t block_rows = std::max<std::size_t>(options.stream_block_rows, 1);
  Eigen::MatrixXd A(static_cast<Eigen::Index>(block_rows), p);
  Eigen::VectorXd b(static_cast<Eigen::Index>(block_rows));
  std::size_t remaining = max_rows;  // rows per equation still wanted
  for (std::size_t r = 0; r < records.size() && remaining > 0; ++r) {
    auto window = fit_window(records[r], model, options.evaluation, options.from, options.to);
    if (auto* d = std::get_if<Diagnostic>(&window)) return *d;
    FitWindow w = std::get<FitWindow>(window);
    // Only the rows wanted are evaluated: the whole-window values (integrals from t0, derivatives
    // of the whole record) of the first rows do not depend on where the window ends.
    if (w.size() > remaining) w.last = w.first + remaining - 1;
    remaining -= w.size();
    std::vector<const ir::Sum*> sums;
    for (std::size_t e : g.equations) {
      for (const auto& term : model.equations[e].terms) sums.push_back(&term.operation);
      sums.push_back(&model.equations[e].known);
    }
    auto whole = prepare_whole_window_values(records[r], model, options.evaluation, w, sums);
    if (auto* d = std::get_if<Diagnostic>(&whole)) return *d;
    BlockEvaluator evaluator(records[r], options.evaluation, w, std::get<WholeWindowValues>(whole));
    for (std::size_t e : g.equations) {
      const ir::Equation& eq = model.equations[e];
      for (std::size_t start = 0; start < w.size(); start += block_rows) {
        const std::size_t m = std::min(block_rows, w.size() - start);
        evaluator.start_block(w.first + start, w.first + start + m);
        A.setZero();
        for (const auto& term : eq.terms) {
          const auto column = static_cast<Eigen::Index>(layout.column(term.parameter, r));
          auto status = evaluator.evaluate(term.operation, std::span<double>(A.col(column).data(), m));
          if (auto* d = std::get_if<Diagnostic>(&status)) return *d;
        }
        auto status = evaluator.evaluate(eq.known, std::span<double>(b.data(), m));
        if (auto* d = std::get_if<Diagnostic>(&status)) return *d;
        const Eigen::VectorXd residuals =
            TriangularAccumulator::residuals_of(A.topRows(static_cast<Eigen::Index>(m)), b.head(static_cast<Eigen::Index>(m)), g.summary);
        block.clear();
        for (std::size_t i = 0; i < m; ++i)
          block.push_back({e, r, records[r].time[w.first + start + i], b(static_cast<Eigen::Index>(i)), residuals(static_cast<Eigen::Index>(i))});
        if (!rows(block)) return std::nullopt;
      }
    }
  }
  return std::nullopt;
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
    if (g.weighted && model.weights)
      out += fmt::format("  residuals weighted by `{}` (eq. 2-1.6)\n", print(model.weights->value));
    else if (g.weighted)
      out += "  residuals weighted by the record's weight column (eq. 2-1.6)\n";
    out += fmt::format("  G(a) = {:.6g} (eq. 2-1.7)   standard error sqrt(G/n) = {:.4g}   residual s.d. = {:.4g}\n", s.G,
                       s.standard_error, s.residual_sd);
    out += fmt::format("  n = {}, p = {}, rank {}   R^2 = {:.6f}   AIC = {:.4g}   BIC = {:.4g}\n", s.n, s.p, s.rank, s.r_squared, s.aic, s.bic);
    out += fmt::format("  condition {:.3g} before scaling, {:.3g} after (section 3-2); about {:.1f} digits lost\n", s.condition_before,
                       s.condition_after, s.digits_lost_estimate);
    out += fmt::format("  arithmetic: {}\n", s.arithmetic);
    if (!g.streamed.empty()) out += fmt::format("  solved: {} (runtime/solve/fit.hpp: FitOptions::stream_above_entries)\n", g.streamed);
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
