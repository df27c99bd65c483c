// The fit (see fit.hpp): per group of equations, the design from design.hpp solved dense or
// streamed, and the rows counted by region.
//
// Relies on: design.hpp (columns, rows, weights and their checks), evaluate.hpp and
// block_evaluator.hpp (the values), least_squares.hpp and triangular_accumulator.hpp (the solve).
// Guarantees: fit.hpp's; the streamed path reports the problem the dense path would meet first.
#include "runtime/solve/fit.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <chrono>
#include <map>
#include <limits>
#include <numeric>
#include <set>
#include <thread>

#include <time.h>

#include "diagnostics/model_catalogue.hpp"
#include "diagnostics/time_text.hpp"
#include "ir/print.hpp"
#include "ir/queries.hpp"
#include "ir/traversal.hpp"
#include "runtime/operators/block_evaluator.hpp"
#include "runtime/operators/operator_choice.hpp"
#include "runtime/operators/running_integrals.hpp"
#include "runtime/parallel_ranges.hpp"
#include "runtime/solve/triangular_accumulator.hpp"
#include "runtime/solve/weak_design.hpp"

namespace sidc {

namespace {

// The group's guards by printed text: those its regions are told by (Table 4-1.1). A guard inside
// another guard's condition shapes that guard's border and tells no region of its own.
std::map<std::string, ir::Factor> guards_of(const ir::Model& model, const std::vector<std::size_t>& equations) {
  std::map<std::string, ir::Factor> guards;
  std::set<const ir::Factor*> in_condition;  // met before their turn: the walk is outer before inner
  const auto collect = [&](const ir::Sum& s) {
    ir::for_each_factor(s, [&](const ir::Factor& f) {
      if (f.kind != ir::FactorKind::guard || in_condition.count(&f)) return;
      guards.emplace(print(f), f);
      ir::for_each_nested_sum(f, [&](const ir::Sum& side) {
        ir::for_each_factor(side, [&](const ir::Factor& inner) { in_condition.insert(&inner); });
      });
    });
  };
  for (std::size_t e : equations) {
    collect(model.equations[e].known);
    for (const auto& p : model.equations[e].terms) collect(p.operation);
  }
  return guards;
}

// Counts the rows of each record's window by which of the group's guards hold there.
std::variant<std::vector<Region>, Diagnostic> count_regions(const ir::Model& model, const std::vector<std::size_t>& equations,
                                                           std::vector<Evaluator>& evaluators) {
  const std::map<std::string, ir::Factor> guards = guards_of(model, equations);
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

// A shared group's region counts travel as one count per combination of guards.
constexpr std::size_t kMostSharedGuards = 16;

// What the streamed path needs besides the model and the records, shared read-only by its threads.
struct StreamPlan {
  const ir::Model& model;
  const std::vector<SampledRecord>& records;
  const std::vector<FitWindow>& windows;
  const FitOptions& options;
  const std::vector<EvaluationOptions>& evaluation;  // per record: its arcs under savgol(auto)
  const DesignBuilder& design;
  std::vector<const ir::Sum*> sums;      // every sum the rows evaluate: the design's, the guards', the weights'
  std::vector<std::string> guard_texts;  // the group's guards, in count_regions' order
  std::vector<ir::Sum> guard_sums;
};

// Where the first problem lies in the dense path's order of evaluation: operation (the known side
// after the operations), term, sample + 1 (0: a problem that is not a value, found on evaluating).
using ProblemKey = std::tuple<std::size_t, std::size_t, std::size_t>;
using Problem = std::optional<std::pair<ProblemKey, Diagnostic>>;

void keep_first(Problem& slot, ProblemKey key, Diagnostic d) {
  if (!slot || key < slot->first) slot.emplace(key, std::move(d));
}

// Row blocks as the design's values. With a slot (the streamed fit), every problem is kept there
// by ProblemKey and the rows go on, since a later block may hold the one the dense path meets
// first; without (the residual pass, over rows the fit accepted), a structural problem stops.
class BlockValues final : public DesignValues {
 public:
  BlockValues(BlockEvaluator& evaluator, const SampledRecord& record, const FitWindow& window, Problem* problems)
      : evaluator_(evaluator), record_(record), window_(window), problems_(problems) {}

  std::optional<Diagnostic> evaluate(const ir::Sum& sum, std::size_t index, const std::string& what, std::span<double> out) override {
    std::optional<NonFiniteValue> bad;
    auto status = evaluator_.evaluate(sum, out, problems_ ? &bad : nullptr);
    if (auto* d = std::get_if<Diagnostic>(&status)) {
      if (!problems_) return std::move(*d);
      keep_first(*problems_, {index, 0, 0}, std::move(*d));
    } else if (bad) {
      keep_first(*problems_, {index, bad->term, bad->sample - window_.first + 1}, non_finite_value(record_, sum, *bad, what));
    }
    return std::nullopt;
  }

 private:
  BlockEvaluator& evaluator_;
  const SampledRecord& record_;
  const FitWindow& window_;
  Problem* problems_;
};

struct StreamWorker {
  explicit StreamWorker(int p) : accumulator(p) {}
  TriangularAccumulator accumulator;
  std::map<std::string, std::size_t> region_rows;  // by a '0'/'1' string, one character per guard
  Problem problem, guard_problem;
  double evaluate_seconds = 0, fold_seconds = 0;
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
// accumulator's own work area, checked, counted by region when asked, and folded. `whole` holds the
// integrals on at least these rows.
void stream_rows(const StreamPlan& plan, const WholeWindowValues& whole, StreamWorker& worker, std::size_t r, std::size_t e,
                 std::size_t begin, std::size_t end, bool count_regions) {
  const SampledRecord& record = plan.records[r];
  const FitWindow& w = plan.windows[r];
  const auto p = static_cast<Eigen::Index>(plan.design.columns().size());
  BlockEvaluator evaluator(record, plan.evaluation[r], w, whole);
  BlockValues values(evaluator, record, w, &worker.problem), guard_values(evaluator, record, w, &worker.guard_problem);
  const std::size_t block_rows = std::max<std::size_t>(plan.options.stream_block_rows, 1);
  std::vector<double> guards(count_regions ? plan.guard_sums.size() * block_rows : 0);
  std::string key(plan.guard_sums.size(), '0');
  std::vector<double> weight_values(plan.model.weights ? block_rows : 0);
  for (std::size_t start = begin; start < end; start += block_rows) {
    const double clock = thread_cpu_seconds();
    const std::size_t m = std::min(block_rows, end - start);
    const std::size_t first = w.first + start;
    evaluator.start_block(first, first + m);
    auto area = worker.accumulator.rows_area(static_cast<Eigen::Index>(m));
    area.setZero();
    plan.design.equation_rows(r, e, values, {area.leftCols(p), area.col(p)});  // problems go to worker.problem
    if (count_regions && !plan.guard_sums.empty()) {
      for (std::size_t g = 0; g < plan.guard_sums.size(); ++g)
        guard_values.evaluate(plan.guard_sums[g], r * plan.guard_sums.size() + g, "a region guard",
                              std::span<double>(guards.data() + g * block_rows, m));
      for (std::size_t i = 0; i < m; ++i) {
        for (std::size_t g = 0; g < plan.guard_sums.size(); ++g) key[g] = guards[g * block_rows + i] != 0.0 ? '1' : '0';
        ++worker.region_rows[key];
      }
    }
    const double evaluated = thread_cpu_seconds();
    worker.evaluate_seconds += evaluated - clock;
    if (worker.problem || worker.guard_problem) continue;  // the fit ends in a diagnostic: fold nothing more
    std::span<const double> expression;
    if (plan.model.weights) {  // checked before streaming (stream_group), so only multiplied here
      auto status = evaluator.evaluate(plan.model.weights->value, std::span<double>(weight_values.data(), m));
      if (auto* d = std::get_if<Diagnostic>(&status)) {  // not after stream_group's check, but never drop rows silently
        keep_first(worker.problem, {0, 0, 0}, std::move(*d));
        continue;
      }
      expression = std::span<const double>(weight_values.data(), m);
    }
    const double* weights = plan.design.row_weights(r, first, expression, weight_values);
    // A rejected block (not finite, negative weight) cannot pass the checks above; if one did, the
    // accumulator counts it and solve() says invalid_input.
    worker.accumulator.fold_rows_area(static_cast<Eigen::Index>(m), weights);
    worker.fold_seconds += thread_cpu_seconds() - evaluated;
  }
}

// A process's rows of a shared group, counted record by record (each record's window times the
// group's equations). With at least as many records as processes, whole records: each boundary of
// the even split moved to the nearest record start, so that the records go whole to the processes,
// in order and balanced by rows (no process carries an integral from the start of a record it
// shares with another); with fewer, the even split in whole blocks (RowShare::share_of).
std::pair<std::size_t, std::size_t> rows_of_part(const std::vector<FitWindow>& windows, std::size_t equations, std::size_t block_rows,
                                                 const RowShare& share) {
  std::vector<std::size_t> starts{0};  // each record's first row, and the end
  for (const auto& w : windows) starts.push_back(starts.back() + w.size() * equations);
  const std::size_t total = starts.back();
  const auto even = [&](int k) { return RowShare::share_of(total, block_rows, k, share.parts()).first; };
  if (windows.size() < static_cast<std::size_t>(share.parts())) return {even(share.part()), even(share.part() + 1)};
  const auto nearest_start = [&](int k) {
    const std::size_t at = even(k);  // even(parts) is the total, itself a start
    const auto after = std::lower_bound(starts.begin(), starts.end(), at);
    if (after == starts.begin()) return *after;
    return at - *(after - 1) <= *after - at ? *(after - 1) : *after;
  };
  return {nearest_start(share.part()), nearest_start(share.part() + 1)};
}

// The streamed path for one group (FitOptions::stream_above_entries).
std::optional<Diagnostic> stream_group(const ir::Model& model, const std::vector<SampledRecord>& records,
                                       const std::vector<FitWindow>& windows, const FitOptions& options,
                                       const std::vector<EvaluationOptions>& evaluation, const DesignBuilder& design,
                                       std::size_t total_rows, GroupFit& g) {
  StreamPlan plan{model, records, windows, options, evaluation, design, {}, {}, {}};
  for (const auto& [text, f] : guards_of(model, g.equations)) {
    plan.guard_texts.push_back(text);
    plan.guard_sums.push_back(ir::factor(f));
  }
  plan.sums = design.sums();
  for (const auto& s : plan.guard_sums) plan.sums.push_back(&s);
  if (model.weights) plan.sums.push_back(&model.weights->value);
  // Integrals are carried stretch by stretch where they can be (memory that does not grow with the
  // record), and prepared over the whole record at once where they cannot (running_integrals.hpp).
  std::vector<RunningIntegrals> integrals;  // per record
  for (std::size_t r = 0; r < records.size(); ++r) {
    auto started = RunningIntegrals::start(records[r], model, evaluation[r], windows[r], plan.sums);
    if (auto* d = std::get_if<Diagnostic>(&started)) return *d;
    integrals.push_back(std::get<RunningIntegrals>(std::move(started)));
  }

  // Weights from an expression: every row's checked first, record by record, as the dense path does.
  if (model.weights) {
    const std::size_t block_rows = std::max<std::size_t>(options.stream_block_rows, 1);
    std::vector<double> values(block_rows);
    for (std::size_t r = 0; r < records.size(); ++r) {
      // Before any stretch: the initial values, and (prepared whole) the integrals; carried ones are
      // never in the weights (RunningIntegrals::carries).
      BlockEvaluator evaluator(records[r], evaluation[r], windows[r], integrals[r].values());
      for (std::size_t start = 0; start < windows[r].size(); start += block_rows) {
        const std::size_t m = std::min(block_rows, windows[r].size() - start), first = windows[r].first + start;
        evaluator.start_block(first, first + m);
        auto status = evaluator.evaluate(model.weights->value, std::span<double>(values.data(), m));
        if (auto* d = std::get_if<Diagnostic>(&status)) return *d;
        if (auto problem = check_weights(model, records[r], std::span<const double>(values.data(), m), first)) return *problem;
      }
    }
  }

  const int threads = stream_thread_count(options);
  const int p = static_cast<int>(design.columns().size());
  std::vector<StreamWorker> workers;
  for (int k = 0; k < threads; ++k) workers.emplace_back(p);
  const std::size_t block_rows = std::max<std::size_t>(options.stream_block_rows, 1);
  int threads_used = 1;
  // Window rows [begin, end) of record r in contiguous parts of whole blocks, one per thread; a
  // short stretch stays on one thread.
  const auto fold_parts = [&](const WholeWindowValues& whole, std::size_t r, std::size_t e, std::size_t begin, std::size_t end) {
    const std::size_t blocks = (end - begin + block_rows - 1) / block_rows;
    const std::size_t parts = std::min<std::size_t>(static_cast<std::size_t>(threads), std::max<std::size_t>(blocks / 4, 1));
    threads_used = std::max(threads_used, static_cast<int>(parts));
    const bool count = e == g.equations.front();
    const auto bound = [&](std::size_t k) { return std::min(end, begin + blocks * k / parts * block_rows); };
    std::vector<std::thread> running;
    for (std::size_t k = 1; k < parts; ++k)
      running.emplace_back([&, k] { stream_rows(plan, whole, workers[k], r, e, bound(k), bound(k + 1), count); });
    stream_rows(plan, whole, workers[0], r, e, begin, bound(1), count);
    for (auto& t : running) t.join();
  };
  // Carried integrals advance over stretches of FitOptions::stream_stretch_rows, each stretch's
  // integrands evaluated and its rows folded on every thread; prepared ones are one stretch.
  // Shared among processes (FitOptions::share, row_share.hpp), this process folds only its share
  // [share_first, share_last) of all rows, counted record by record and equation by equation.
  std::size_t folded = 0, to_fold = 0;
  for (const auto& w : windows) to_fold += w.size() * g.equations.size();
  RowShare* share = options.share && options.share->parts() > 1 && plan.guard_sums.size() <= kMostSharedGuards ? options.share : nullptr;
  const auto [share_first, share_last] = share ? rows_of_part(windows, g.equations.size(), block_rows, *share)
                                               : std::pair<std::size_t, std::size_t>{0, to_fold};
  bool has_problem = false;  // shared: a problem met, to be named by every process alike (below)
  std::size_t offset = 0;    // rows of the records and equations before this one
  for (std::size_t r = 0; r < records.size() && !has_problem; ++r) {
    RunningIntegrals& running = integrals[r];
    const std::size_t n = windows[r].size(), stretch = running.stretch_rows(options.stream_stretch_rows);
    for (std::size_t e : g.equations) {
      const std::size_t mine_first = std::clamp(share_first, offset, offset + n) - offset;
      const std::size_t mine_last = std::clamp(share_last, offset, offset + n) - offset;
      offset += n;
      if (mine_first == mine_last) continue;  // none of this equation's rows on this record are ours
      running.restart();  // from t0 again for each equation
      for (std::size_t begin = 0; begin < mine_last; begin += stretch) {
        const std::size_t end = std::min(mine_last, begin + stretch);
        if (auto problem = running.advance(end, threads, block_rows)) {
          if (!share) return problem;
          has_problem = true;
          break;
        }
        if (end > mine_first) fold_parts(running.values(), r, e, std::max(begin, mine_first), end);
        folded += end - std::max(begin, mine_first);
        if (options.progress) options.progress(folded, share_last - share_first);
      }
      // The dense path's first problem: the smallest key over the parts of this record and equation.
      Problem first;
      for (auto& w : workers)
        if (w.problem && (!first || w.problem->first < first->first)) first = w.problem;
      if (first && !share) return first->second;
      has_problem = has_problem || first;
      if (has_problem) break;
    }
  }
  // count_regions runs after the whole design: a guard's problem only after every operation of
  // every record, ranked by record, guard and row as count_regions meets them.
  {
    Problem first;
    for (auto& w : workers)
      if (w.guard_problem && (!first || w.guard_problem->first < first->first)) first = w.guard_problem;
    if (first && !share) return first->second;
    has_problem = has_problem || first;
  }
  for (std::size_t k = 1; k < workers.size(); ++k) workers[0].accumulator.merge(workers[k].accumulator);
  std::map<std::string, std::size_t> masks;
  for (auto& w : workers)
    for (const auto& [mask, rows] : w.region_rows) masks[mask] += rows;
  for (const auto& w : workers) {
    g.evaluate_seconds += w.evaluate_seconds;
    g.fold_seconds += w.fold_seconds;
  }
  if (share) {
    // Region counts by mask (2^guards of them) and the CPU seconds, summed over the processes.
    const std::size_t guards = plan.guard_sums.size();
    std::vector<double> sums(std::size_t{1} << guards, 0.0);
    for (const auto& [mask, rows] : masks) {
      std::size_t bits = 0;
      for (std::size_t k = 0; k < guards; ++k) bits |= mask[k] == '1' ? std::size_t{1} << k : 0;
      sums[bits] = static_cast<double>(rows);
    }
    sums.push_back(g.evaluate_seconds);
    sums.push_back(g.fold_seconds);
    const RowShare::Combined combined = share->combine(workers[0].accumulator, sums, has_problem);
    if (combined.outcome == RowShare::Outcome::stopped) return diag::error("stopped", {}, combined.why);
    if (combined.outcome == RowShare::Outcome::problem) {
      // Some process met a problem in its rows: every process evaluates all rows alone, and so names
      // the problem a single process names (a failing fit pays twice, a good one never).
      FitOptions alone = options;
      alone.share = nullptr;
      g.regions.clear();
      g.evaluate_seconds = g.fold_seconds = 0;
      if (auto problem = stream_group(model, records, windows, alone, evaluation, design, total_rows, g)) return problem;
      return diag::error("stopped", {}, "the processes disagree: a problem one of them met in its rows is not met by one process alone");
    }
    masks.clear();
    for (std::size_t bits = 0; bits + 2 < sums.size(); ++bits) {
      if (sums[bits] == 0) continue;
      std::string mask(guards, '0');
      for (std::size_t k = 0; k < guards; ++k) mask[k] = bits & (std::size_t{1} << k) ? '1' : '0';
      masks[mask] = static_cast<std::size_t>(sums[bits]);
    }
    g.evaluate_seconds = sums[sums.size() - 2];
    g.fold_seconds = sums.back();
  }
  std::map<std::string, std::size_t> counts;
  for (const auto& [mask, rows] : masks) {
    std::string text;
    for (std::size_t k = 0; k < mask.size(); ++k)
      if (mask[k] == '1') text += (text.empty() ? "" : " and ") + plan.guard_texts[k];
    counts[text.empty() ? "(no guard)" : text] += rows;
  }
  for (auto& [text, rows] : counts) g.regions.push_back({text, rows});
  if (auto problem = design.too_few_rows(total_rows, evaluation.front())) return problem;

  const auto clock = std::chrono::steady_clock::now();
  g.summary = workers[0].accumulator.solve(g.columns, options.least_squares);
  g.solve_seconds = seconds_since(clock);
  design.label(g.summary);
  g.hac.note = "not computed for a streamed fit (its rows are folded into the triangle, not kept)";
  g.streamed = fmt::format("streamed QR over {} rows in blocks of {} rows on {} thread{}", total_rows, block_rows, threads_used,
                           threads_used == 1 ? "" : "s");
  if (share)
    g.streamed = fmt::format("streamed QR over {} rows in blocks of {} rows on {} processes (MPI ranks) of {} thread{} each, "
                             "their factors merged (TSQR)", total_rows, block_rows, share->parts(), threads_used, threads_used == 1 ? "" : "s");
  return std::nullopt;
}

// `set weights = <expression>` (eq. 2-1.6) on each record's window; empty when the model sets none.
std::variant<std::vector<std::vector<double>>, Diagnostic> expression_weights_by_record(const ir::Model& model,
                                                                                       std::vector<Evaluator>& evaluators) {
  std::vector<std::vector<double>> out(model.weights ? evaluators.size() : 0);
  for (std::size_t r = 0; r < out.size(); ++r) {
    auto values = expression_weights(model, evaluators[r]);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    out[r] = std::get<std::vector<double>>(std::move(values));
  }
  return out;
}

// An equation whose known side is zero on every row of the group (a record column of zeros): least
// squares would return every parameter 0 with G = 0, R^2 undefined and AIC = -inf, and call it a
// fit. Refused, naming the equation and the records. Needs g.known and g.row_equation (dense, weak).
std::optional<Diagnostic> zero_known_side(const ir::Model& model, const std::vector<SampledRecord>& records, const GroupFit& g) {
  for (std::size_t e : g.equations) {
    bool has_rows = false, non_zero = false;
    for (std::size_t i = 0; i < g.known.size() && !non_zero; ++i) {
      if (g.row_equation[i] != e) continue;
      has_rows = true;
      non_zero = g.known[i] != 0;
    }
    if (!has_rows || non_zero) continue;
    std::string names;
    for (std::size_t r = 0; r < records.size(); ++r)
      names += fmt::format("{}`{}`", r == 0 ? "" : r + 1 == records.size() ? " and " : ", ", records[r].path);
    return diag::known_side_zero(model.equations[e].span, e + 1, print(model.equations[e].known), names);
  }
  return std::nullopt;
}

// A group of weak-form equations (weak_design.hpp): always dense, one row per subdomain.
std::optional<Diagnostic> fit_weak_group(const ir::Model& model, const std::vector<SampledRecord>& records,
                                         std::vector<Evaluator>& evaluators, const DesignBuilder& design, const FitOptions& options,
                                         const std::vector<OperatorReport>& operators, GroupFit& g) {
  auto expression = expression_weights_by_record(model, evaluators);
  if (auto* d = std::get_if<Diagnostic>(&expression)) return *d;
  const std::vector<TestFunctionGrid>* given = nullptr;
  if (options.same_choices_as)
    for (const auto& other : options.same_choices_as->groups)
      if (other.equations == g.equations && other.weak_grids.size() == records.size()) given = &other.weak_grids;
  auto made = weak_design(model, records, evaluators, design, g.equations, std::get<std::vector<std::vector<double>>>(expression), options.share,
                          given);
  if (auto* d = std::get_if<Diagnostic>(&made)) return *d;
  WeakDesign& w = std::get<WeakDesign>(made);
  for (std::size_t r = 0; r < records.size(); ++r) {
    g.records[r].rows = w.grids[r].centres.size();
    g.subdomains.push_back(describe(w.grids[r], records[r].step));
  }
  g.weak_grids = w.grids;
  g.row_equation = std::move(w.row_equation);
  g.row_record = std::move(w.row_record);
  g.row_time = std::move(w.row_time);
  g.known.assign(w.b.data(), w.b.data() + w.b.size());
  auto regions = count_regions(model, g.equations, evaluators);
  if (auto* d = std::get_if<Diagnostic>(&regions)) return *d;
  g.regions = std::get<std::vector<Region>>(std::move(regions));
  if (auto problem = design.too_few_rows(static_cast<std::size_t>(w.b.size()), options.evaluation)) return problem;
  if (auto problem = zero_known_side(model, records, g)) return problem;
  g.summary = solve_least_squares(w.A, w.b, g.columns, g.weighted ? &w.weights : nullptr, options.least_squares);
  if (!options.weak_covariance) {
    g.weak_weighting.note = "rows not weighted by their noise covariance: " + options.weak_covariance_off;
  } else if (g.weighted) {
    g.weak_weighting.note = "rows not weighted by their noise covariance: the rows carry weights of their own (eq. 2-1.6)";
  } else {
    std::vector<NoiseBySignal> noise(records.size());
    for (std::size_t r = 0; r < records.size() && r < operators.size(); ++r)
      for (const auto& s : operators[r].noise) noise[r][s.signal] = s.level.sigma;
    auto [summary, how] = weight_weak_rows(model, evaluators, design, g.equations, w, noise, g.summary, g.columns, options.least_squares);
    g.summary = std::move(summary);
    g.weak_weighting = std::move(how);
  }
  design.label(g.summary);
  return std::nullopt;
}

}  // namespace

std::vector<std::size_t> neighbour_runs(const GroupFit& g) {
  std::vector<std::size_t> starts;
  for (std::size_t i = 0; i < g.row_record.size(); ++i)
    if (i == 0 || g.row_record[i] != g.row_record[i - 1] || g.row_equation[i] != g.row_equation[i - 1]) starts.push_back(i);
  return starts;
}

int stream_thread_count(const FitOptions& options) {
  if (options.stream_threads > 0) return options.stream_threads;
  return core_count();
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
  std::vector<EvaluationOptions> evaluation;  // per record: under savgol(auto), its own arcs
  for (const auto& r : records) {
    if (const FitSummary* given = options.same_choices_as) {
      if (given->operators.size() != records.size()) throw std::logic_error("fit: the choices given are of other records");
      summary.operators.push_back(given->operators[summary.operators.size()]);
    } else {
      auto chosen = choose_operators(r, model, options.evaluation);
      if (auto* d = std::get_if<Diagnostic>(&chosen)) return *d;
      summary.operators.push_back(std::get<OperatorReport>(std::move(chosen)));
    }
    evaluation.push_back(with_arcs(options.evaluation, summary.operators.back()));
    auto w = fit_window(r, model, evaluation.back(), options.from, options.to);
    if (auto* d = std::get_if<Diagnostic>(&w)) return *d;
    windows.push_back(std::get<FitWindow>(w));
  }
  std::vector<Evaluator> evaluators;
  evaluators.reserve(records.size());
  for (std::size_t r = 0; r < records.size(); ++r) evaluators.emplace_back(records[r], model, evaluation[r], windows[r]);

  for (const auto& members : equation_groups(model)) {
    GroupFit g;
    g.equations = members;
    const DesignBuilder design(model, records, members);
    g.columns = design.column_names();
    g.column_parameters = design.column_indices();
    std::size_t total_rows = 0;
    for (std::size_t r = 0; r < records.size(); ++r) {
      const FitWindow& w = windows[r];
      total_rows += w.size() * members.size();
      g.records.push_back({records[r].path, records[r].time[w.first], records[r].time[w.last], records[r].step, w.first, w.size()});
    }
    g.weighted = model.weights || std::any_of(records.begin(), records.end(), [](const SampledRecord& r) { return !r.weights.empty(); });
    auto weak = is_weak_group(model, members);
    if (auto* d = std::get_if<Diagnostic>(&weak)) return *d;
    if (std::get<bool>(weak)) {
      if (auto problem = fit_weak_group(model, records, evaluators, design, options, summary.operators, g)) return *problem;
      summary.groups.push_back(std::move(g));
      continue;
    }
    if (total_rows * g.columns.size() > options.stream_above_entries) {
      if (auto problem = stream_group(model, records, windows, options, evaluation, design, total_rows, g)) return *problem;
      summary.groups.push_back(std::move(g));
      continue;
    }
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(total_rows), static_cast<Eigen::Index>(g.columns.size()));
    Eigen::VectorXd b(static_cast<Eigen::Index>(total_rows));
    Eigen::VectorXd weights = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(total_rows));
    auto by_record = expression_weights_by_record(model, evaluators);
    if (auto* d = std::get_if<Diagnostic>(&by_record)) return *d;
    const auto& weights_of_expression = std::get<std::vector<std::vector<double>>>(by_record);  // per record, on its window
    g.row_equation.reserve(total_rows);
    g.row_record.reserve(total_rows);
    g.row_time.reserve(total_rows);
    g.known.reserve(total_rows);
    Eigen::Index row = 0;
    for (std::size_t r = 0; r < records.size(); ++r) {
      const std::span<const double> expression = model.weights ? std::span<const double>(weights_of_expression[r]) : std::span<const double>();
      if (auto problem = design.window_rows(r, evaluators[r], expression, A, b, weights, row)) return *problem;
      const FitWindow& w = windows[r];
      for (std::size_t e : members)
        for (std::size_t i = 0; i < w.size(); ++i, ++row) {
          g.row_equation.push_back(e);
          g.row_record.push_back(r);
          g.row_time.push_back(records[r].time[w.first + i]);
          g.known.push_back(b(row));
        }
    }
    auto regions = count_regions(model, members, evaluators);
    if (auto* d = std::get_if<Diagnostic>(&regions)) return *d;
    g.regions = std::get<std::vector<Region>>(std::move(regions));
    if (auto problem = design.too_few_rows(total_rows, evaluation.front())) return *problem;
    if (auto problem = zero_known_side(model, records, g)) return *problem;
    std::vector<std::string> paths;
    for (const auto& r : records) paths.push_back(r.path);
    g.drift = find_drift(model, members, g.columns, g.column_parameters, A, b, g.row_equation, g.row_record, g.row_time, paths);
    g.summary = solve_least_squares(A, b, g.columns, g.weighted ? &weights : nullptr, options.least_squares);
    design.label(g.summary);
    if (!is_static(model)) {  // a static model's rows are observations, not neighbours in time
      HacOptions hac;
      hac.confidence_level = options.least_squares.confidence_level;
      g.hac = hac_covariance(A, g.summary.residuals, g.weighted ? &weights : nullptr, neighbour_runs(g), g.summary, hac);
    }
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
  // Streamed: evaluate every block again, as stream_rows did, and apply the estimates; a batch of
  // blocks at a time on the cores (each block's rows as one thread makes them), handed on in order.
  const DesignBuilder design(model, records, g.equations);
  const auto p = static_cast<Eigen::Index>(design.columns().size());
  const std::size_t block_rows = std::max<std::size_t>(options.stream_block_rows, 1);
  const std::size_t batch = 4 * static_cast<std::size_t>(core_count());  // blocks evaluated side by side
  std::vector<std::vector<ResidualRow>> batch_rows(batch);
  std::vector<std::optional<Diagnostic>> batch_problems(batch);
  std::size_t remaining = max_rows;  // rows per equation still wanted
  for (std::size_t r = 0; r < records.size() && remaining > 0; ++r) {
    auto chosen = operators_for_record(options.evaluation, records[r], model);
    if (auto* d = std::get_if<Diagnostic>(&chosen)) return *d;
    const EvaluationOptions& evaluation = std::get<EvaluationOptions>(chosen);
    auto window = fit_window(records[r], model, evaluation, options.from, options.to);
    if (auto* d = std::get_if<Diagnostic>(&window)) return *d;
    FitWindow w = std::get<FitWindow>(window);
    // Only the rows wanted are evaluated: the whole-window values (integrals from t0, derivatives
    // of the whole record) of the first rows do not depend on where the window ends.
    if (w.size() > remaining) w.last = w.first + remaining - 1;
    remaining -= w.size();
    // The integrals as the fit had them: carried stretch by stretch, or the whole window at once.
    auto started = RunningIntegrals::start(records[r], model, evaluation, w, design.sums());
    if (auto* d = std::get_if<Diagnostic>(&started)) return *d;
    RunningIntegrals& running = std::get<RunningIntegrals>(started);
    const std::size_t stretch = running.stretch_rows(options.stream_stretch_rows);
    for (std::size_t e : g.equations) {
      running.restart();
      for (std::size_t begin = 0; begin < w.size(); begin += stretch) {
        const std::size_t end = std::min(w.size(), begin + stretch);
        if (auto problem = running.advance(end, 1, block_rows)) return problem;
        const std::size_t blocks = (end - begin + block_rows - 1) / block_rows;
        for (std::size_t first_block = 0; first_block < blocks; first_block += batch) {
          const std::size_t in_batch = std::min(batch, blocks - first_block);
          const auto evaluate = [&](std::size_t from, std::size_t to) {
            BlockEvaluator evaluator(records[r], evaluation, w, running.values());
            BlockValues values(evaluator, records[r], w, nullptr);
            Eigen::MatrixXd A(static_cast<Eigen::Index>(block_rows), p);
            Eigen::VectorXd b(static_cast<Eigen::Index>(block_rows));
            for (std::size_t k = from; k < to; ++k) {
              const std::size_t start = begin + (first_block + k) * block_rows, m = std::min(block_rows, end - start);
              const auto count = static_cast<Eigen::Index>(m);
              evaluator.start_block(w.first + start, w.first + start + m);
              A.setZero();
              batch_rows[k].clear();
              if ((batch_problems[k] = design.equation_rows(r, e, values, {A.topRows(count), b.head(count)}))) return;  // later blocks are not wanted
              const Eigen::VectorXd residuals = TriangularAccumulator::residuals_of(A.topRows(count), b.head(count), g.summary);
              for (std::size_t i = 0; i < m; ++i)
                batch_rows[k].push_back({e, r, records[r].time[w.first + start + i], b(static_cast<Eigen::Index>(i)),
                                         residuals(static_cast<Eigen::Index>(i))});
            }
          };
          std::fill(batch_problems.begin(), batch_problems.end(), std::nullopt);
          for_parallel_ranges(in_batch, in_batch * block_rows * static_cast<std::size_t>(p) * static_cast<std::size_t>(p), evaluate);
          for (std::size_t k = 0; k < in_batch; ++k) {
            if (batch_problems[k]) return batch_problems[k];
            if (!rows(batch_rows[k])) return std::nullopt;
          }
        }
      }
    }
  }
  return std::nullopt;
}

std::vector<Diagnostic> statistics_warnings(const ir::Model& model, const FitSummary& summary) {
  std::vector<Diagnostic> warnings;
  for (const GroupFit& g : summary.groups) {
    const std::vector<std::string> found = unrepresentable_statistics(g.summary);
    if (found.empty() || g.equations.empty()) continue;
    std::string equations = g.equations.size() == 1 ? "equation " : "equations ";
    for (std::size_t k = 0; k < g.equations.size(); ++k)
      equations += fmt::format("{}{}", k == 0 ? "" : k + 1 == g.equations.size() ? " and " : ", ", g.equations[k] + 1);
    std::string statistics;
    for (std::size_t k = 0; k < found.size(); ++k) statistics += (k == 0 ? "" : ", ") + found[k];
    warnings.push_back(diag::statistics_not_finite(model.equations[g.equations.front()].span, equations, statistics));
  }
  return warnings;
}

bool FitSummary::is_solution_usable() const {
  return std::all_of(groups.begin(), groups.end(), [](const GroupFit& g) { return g.summary.is_solution_usable(); });
}

std::string FitSummary::brief_report() const {
  std::string out;
  for (const auto& g : groups) out += g.summary.brief_report() + "\n";
  return out;
}

namespace {

// A note as report lines of at most 118 characters, indented by two (empty for an empty note).
std::string wrap_note(const std::string& note) {
  std::string out, line;
  std::size_t from = 0;
  while (from < note.size()) {
    std::size_t to = note.find(' ', from);
    if (to == std::string::npos) to = note.size();
    const std::string word = note.substr(from, to - from);
    if (!line.empty() && line.size() + 1 + word.size() > 116) {
      out += "  " + line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
    from = to + 1;
  }
  if (!line.empty()) out += "  " + line + "\n";
  return out;
}

// The HAC intervals beside the classical ones, and which to trust (hac_covariance.hpp).
std::string hac_report(const GroupFit& g) {
  const HacEstimate& h = g.hac;
  // The weak form has its own note above; an unusable fit says so itself.
  if (!g.subdomains.empty() || !g.summary.is_solution_usable() || (!h.computed && h.note.empty())) return "";
  if (!h.computed) return fmt::format("  Newey-West (HAC) intervals: {}\n", h.note);
  // One rule decides which intervals to trust, the residual analysis' (trust_newey_west: its "for the
  // intervals" line); this section gives the numbers it refers to.
  std::string out = fmt::format(
      "  Newey-West (HAC) intervals, which allow for autocorrelated rows (residual lag-1 autocorrelation {:.3g}, 99% band of\n"
      "  independent rows +-{:.2g}): the ones to trust when the residual analysis below finds the residuals autocorrelated,\n"
      "  or when they are more than twice as wide as the classical ones (scores prewhitened by an AR(1) each{}, Bartlett\n"
      "  kernel of bandwidth {:.1f} rows by Andrews' plug-in)\n",
      h.lag1_autocorrelation, h.band, h.prewhitening_clamped ? ", its coefficient capped at 0.97" : "", h.bandwidth);
  out += fmt::format("  {:<14} {:>15}   {:>31}   {}\n", "parameter", "HAC std. error", fmt::format("{:g}% confidence interval", 100 * h.level),
                     "x classical");
  for (std::size_t j = 0; j < g.summary.parameters.size() && j < h.standard_errors.size(); ++j) {
    const auto& p = g.summary.parameters[j];
    const double ratio = p.standard_error > 0 ? h.standard_errors[j] / p.standard_error : std::numeric_limits<double>::quiet_NaN();
    out += fmt::format("  {:<14} {:>15.4g}   [{:>13.6g}, {:>13.6g}]   {:.3g}\n", p.name, h.standard_errors[j], h.ci_low[j], h.ci_high[j], ratio);
  }
  return out;
}

}  // namespace

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
                         eq.weak ? " (weak form)"
                         : eq.integrations ? fmt::format(" (integrated {} time{})", eq.integrations, eq.integrations == 1 ? "" : "s") : "",
                         text);
    }
    for (std::size_t r = 0; r < g.subdomains.size(); ++r)
      out += fmt::format("  weak form on {}: {}\n", g.records[r].path, g.subdomains[r]);
    if (!g.subdomains.empty() && g.weak_weighting.applied)
      out += wrap_note(g.weak_weighting.note);
    else if (!g.subdomains.empty())
      out += wrap_note(g.weak_weighting.note) +
             "  (neighbouring subdomains overlap, so their rows are not independent: the standard errors and intervals below are\n"
             "  those of independent rows, which held the truth in 87-100% of known-truth cases at 1% noise (docs/accuracy.md);\n"
             "  the fitted equations solved against the record (validation) are the test to trust)\n";
    for (const auto& r : g.records) {
      if (is_static(model))
        out += fmt::format("  record {}: rows {} to {}, n = {} per equation\n", r.path, r.first_sample + 1, r.first_sample + r.rows, r.rows);
      else
        out += fmt::format("  record {}: t0 = {} to {}, step {:g}, n = {} per equation\n", r.path, time_text(r.t0, r.step, 6), time_text(r.t_last, r.step, 6),
                           r.step, r.rows);
    }
    if (!g.regions.empty()) {
      out += "  rows by region (Table 4-1.1):\n";
      for (const auto& r : g.regions) out += fmt::format("    {:>6}  {}\n", r.rows, r.guards);
    }
    // A unit column only for models that give units (docs/language.md, "Units").
    const bool units = std::any_of(model.parameters.begin(), model.parameters.end(), [](const ir::Parameter& p) { return p.unit.has_value(); });
    out += fmt::format("  {:<14} {:>15} {:>13}   {:>31}{}\n", "parameter", "estimate", "std. error",
                       fmt::format("{:g}% confidence interval", 100 * 0.95), units ? "   unit" : "");
    for (const auto& p : s.parameters) {
      const std::string unit = units ? parameter_unit(model, p.name) : std::string();
      out += fmt::format("  {:<14} {:>15.6g} {:>13.4g}   [{:>13.6g}, {:>13.6g}]{}\n", p.name, p.value, p.standard_error, p.ci_low,
                         p.ci_high, unit.empty() ? "" : "   " + unit);
    }
    out += hac_report(g);
    if (g.weighted && model.weights)
      out += fmt::format("  residuals weighted by `{}` (eq. 2-1.6)\n", print(model.weights->value));
    else if (g.weighted)
      out += "  residuals weighted by the record's weight column (eq. 2-1.6)\n";
    out += fmt::format("  G(a) = {:.6g} (eq. 2-1.7)   standard error sqrt(G/n) = {:.4g}   residual s.d. = {:.4g}\n", s.G,
                       s.standard_error, s.residual_sd);
    // Both R^2: an uncentred 1.000000 beside a centred 0.3 says the known side is mostly its mean or a drift.
    out += fmt::format("  n = {}, p = {}, rank {}   R^2 = {:.6f} ({}; {} {:.6f})   AIC = {:.4g}   BIC = {:.4g}\n", s.n, s.p, s.rank, s.r_squared,
                       s.r_squared_centred ? "centred" : "uncentred", s.r_squared_centred ? "uncentred" : "centred",
                       s.r_squared_centred ? s.uncentred_r_squared : s.centred_r_squared, s.aic, s.bic);
    out += fmt::format("  condition {:.3g} before scaling, {:.3g} after (section 3-2); about {:.1f} digits lost\n", s.condition_before,
                       s.condition_after, s.digits_lost_estimate);
    out += fmt::format("  arithmetic: {}\n", s.arithmetic);
    if (!g.streamed.empty()) out += fmt::format("  solved: {} (its design exceeds FitOptions::stream_above_entries)\n", g.streamed);
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
