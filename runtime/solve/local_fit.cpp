// Local fits (see local_fit.hpp): each record's rows produced a chunk of samples at a time, in
// the global fit's order and weights, and slid through a SlidingFactor piece by piece on threads.
#include "runtime/solve/local_fit.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <numeric>
#include <thread>

#include <fmt/format.h>

#include "diagnostics/data_catalogue.hpp"
#include "runtime/not_a_number.hpp"
#include "runtime/operators/block_evaluator.hpp"
#include "runtime/operators/operator_choice.hpp"
#include "runtime/parallel_ranges.hpp"
#include "runtime/solve/design.hpp"
#include "runtime/solve/sliding_factor.hpp"
#include "runtime/solve/weak_design.hpp"

namespace sidc {
namespace {

// Rows of a window's samples, weighted (eq. 2-1.6): each row p values and its known side.
class RowCursor {
 public:
  virtual ~RowCursor() = default;
  // The rows of fit-window sample s (relative to the window): k rows of p + 1 values, k >= 0.
  virtual std::span<const double> rows_at(std::size_t s) = 0;
  virtual std::optional<Diagnostic> problem() const = 0;
};

// Block values with the dense path's words for a value that is not finite.
class ChunkValues final : public DesignValues {
 public:
  ChunkValues(BlockEvaluator& evaluator, const SampledRecord& record) : evaluator_(evaluator), record_(record) {}
  std::optional<Diagnostic> evaluate(const ir::Sum& sum, std::size_t, const std::string& what, std::span<double> out) override {
    std::optional<NonFiniteValue> bad;
    auto status = evaluator_.evaluate(sum, out, &bad);
    if (auto* d = std::get_if<Diagnostic>(&status)) return std::move(*d);
    if (bad) return non_finite_value(record_, sum, *bad, what);
    return std::nullopt;
  }

 private:
  BlockEvaluator& evaluator_;
  const SampledRecord& record_;
};

// `record` alone, for a design of its own (its own integration constants): its columns borrowed,
// not copied (a record of 10^7 samples is fitted window by window without a second copy); the
// caller's record outlives the local fit.
SampledRecord alone(const SampledRecord& record) {
  static const auto lent = std::make_shared<const int>(0);  // borrowed memory is the caller's: nothing to keep alive
  SampledRecord out;
  out.path = record.path;
  out.step = record.step;
  out.time = Column::borrowed(record.time, lent);
  for (const auto& [name, values] : record.signals) out.signals.emplace(name, Column::borrowed(values, lent));
  out.columns = record.columns;
  out.weights = record.weights;
  out.weights_column = record.weights_column;
  return out;
}

// What a record's rows come from, shared read-only by the threads' cursors.
struct RowSource {
  RowSource(const ir::Model& m, const SampledRecord& record, std::vector<std::size_t> group)
      : model(m), one{alone(record)}, equations(std::move(group)) {}
  const ir::Model& model;
  std::vector<SampledRecord> one;  // the record alone: its own integration constants
  EvaluationOptions evaluation;
  FitWindow window;
  std::unique_ptr<DesignBuilder> design;
  std::vector<std::size_t> equations;
  // Derivative and integrated forms: the whole-window values the blocks slice.
  WholeWindowValues whole;
  // Weak form: every row, ordered by subdomain centre; rows of sample s are [first[s], first[s+1]).
  bool weak = false;
  std::vector<double> weak_rows;
  std::vector<std::size_t> weak_first;
  int p() const { return static_cast<int>(design->columns().size()); }
};

// Derivative and integrated forms: chunks of samples evaluated by a BlockEvaluator.
class PointCursor final : public RowCursor {
 public:
  explicit PointCursor(const RowSource& rows)
      : rows_(rows), evaluator_(rows.one[0], rows.evaluation, rows.window, rows.whole), values_(evaluator_, rows.one[0]) {}

  std::span<const double> rows_at(std::size_t s) override {
    if (s < first_ || s >= last_) fill(s);
    const std::size_t width = rows_.equations.size() * static_cast<std::size_t>(rows_.p() + 1);
    return {buffer_.data() + (s - first_) * width, width};
  }
  std::optional<Diagnostic> problem() const override { return problem_; }

 private:
  static constexpr std::size_t kChunk = 1024;

  void fill(std::size_t s) {
    const FitWindow& w = rows_.window;
    const auto p = static_cast<Eigen::Index>(rows_.p());
    first_ = s;
    last_ = std::min(w.size(), s + kChunk);
    const std::size_t m = last_ - first_, E = rows_.equations.size();
    const auto count = static_cast<Eigen::Index>(m);
    buffer_.assign(m * E * static_cast<std::size_t>(p + 1), 0.0);
    if (problem_) return;
    evaluator_.start_block(w.first + first_, w.first + last_);
    A_.resize(count, p);
    b_.resize(count);
    weights_.resize(m);
    std::span<const double> expression;
    if (rows_.model.weights) {
      auto status = evaluator_.evaluate(rows_.model.weights->value, std::span<double>(weights_.data(), m));
      if (auto* d = std::get_if<Diagnostic>(&status)) return void(problem_ = *d);
      if (auto bad = check_weights(rows_.model, rows_.one[0], weights_, w.first + first_)) return void(problem_ = *bad);
      expression = weights_;
    }
    const double* weight = rows_.design->row_weights(0, w.first + first_, expression, weights_);
    for (std::size_t e = 0; e < E; ++e) {
      A_.setZero();
      if (auto d = rows_.design->equation_rows(0, rows_.equations[e], values_, {A_, b_})) return void(problem_ = *d);
      for (std::size_t i = 0; i < m; ++i) {
        double* row = buffer_.data() + (i * E + e) * static_cast<std::size_t>(p + 1);
        const double v = weight ? weight[i] : 1.0;
        for (Eigen::Index j = 0; j < p; ++j) row[j] = v * A_(static_cast<Eigen::Index>(i), j);
        row[p] = v * b_(static_cast<Eigen::Index>(i));
      }
    }
  }

  const RowSource& rows_;
  BlockEvaluator evaluator_;
  ChunkValues values_;
  std::size_t first_ = 1, last_ = 0;  // empty: the first call fills
  std::vector<double> buffer_, weights_;
  Eigen::MatrixXd A_;
  Eigen::VectorXd b_;
  std::optional<Diagnostic> problem_;
};

// Weak form: the rows made once for the whole record.
class WeakCursor final : public RowCursor {
 public:
  explicit WeakCursor(const RowSource& rows) : rows_(rows) {}
  std::span<const double> rows_at(std::size_t s) override {
    const std::size_t width = static_cast<std::size_t>(rows_.p() + 1);
    return {rows_.weak_rows.data() + rows_.weak_first[s] * width, (rows_.weak_first[s + 1] - rows_.weak_first[s]) * width};
  }
  std::optional<Diagnostic> problem() const override { return std::nullopt; }

 private:
  const RowSource& rows_;
};

std::unique_ptr<RowCursor> cursor(const RowSource& rows) {
  if (rows.weak) return std::make_unique<WeakCursor>(rows);
  return std::make_unique<PointCursor>(rows);
}

std::optional<Diagnostic> prepare_weak_rows(RowSource& rows) {
  Evaluator evaluator(rows.one[0], rows.model, rows.evaluation, rows.window);
  std::vector<double> expression;
  if (rows.model.weights) {
    auto values = expression_weights(rows.model, evaluator);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    expression = std::get<std::vector<double>>(std::move(values));
  }
  auto made = weak_record_design(rows.model, rows.one, 0, evaluator, *rows.design, rows.equations, expression);
  if (auto* d = std::get_if<Diagnostic>(&made)) return *d;
  const WeakDesign& design = std::get<WeakDesign>(made);
  const SampledRecord& record = rows.one[0];
  const auto width = static_cast<std::size_t>(rows.p() + 1);
  const std::size_t n = rows.window.size();
  std::vector<std::size_t> sample(static_cast<std::size_t>(design.b.size()));
  for (std::size_t i = 0; i < sample.size(); ++i) {
    const double at = std::round((design.row_time[i] - record.time[rows.window.first]) / record.step);
    sample[i] = static_cast<std::size_t>(std::clamp(at, 0.0, static_cast<double>(n - 1)));
  }
  std::vector<std::size_t> order(sample.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return sample[a] < sample[b]; });
  rows.weak_rows.resize(order.size() * width);
  rows.weak_first.assign(n + 1, 0);
  for (std::size_t k = 0; k < order.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(order[k]);
    const double v = design.weights(i);
    double* row = rows.weak_rows.data() + k * width;
    for (Eigen::Index j = 0; j + 1 < static_cast<Eigen::Index>(width); ++j) row[j] = v * design.A(i, j);
    row[width - 1] = v * design.b(i);
    ++rows.weak_first[sample[order[k]] + 1];
  }
  std::partial_sum(rows.weak_first.begin(), rows.weak_first.end(), rows.weak_first.begin());
  rows.weak = true;
  return std::nullopt;
}

bool is_zero_row(const double* row, int p) {
  for (int j = 0; j <= p; ++j)
    if (row[j] != 0) return false;
  return true;
}

int thread_count(const FitOptions& options, const LocalFitOptions& local) {
  const int asked = local.threads > 0 ? local.threads : options.stream_threads;
  if (asked > 0) return asked;
  return core_count();
}

// One record's windows for one group, and what the pieces found.
struct Slide {
  const RowSource& rows;
  const LocalFitOptions& local;
  double tolerance;
  std::size_t W = 0, S = 1, windows = 0, per_piece = 1;
  LocalRecordFit& out;
  std::vector<std::vector<double>> border;  // per piece: its estimate of the next piece's first window
  std::atomic<std::size_t> fresh{0}, refused{0};
  std::mutex problem_lock;
  std::optional<std::pair<std::size_t, Diagnostic>> problem;  // by piece: the earliest

  void keep(const SlidingSolution& solution, std::size_t k, double t_center, double n) {
    const std::size_t p = static_cast<std::size_t>(rows.p());
    out.t_center[k] = t_center;
    out.G[k] = solution.G;
    out.n[k] = n;
    out.rank[k] = solution.rank;
    for (std::size_t j = 0; j < p; ++j) {
      out.estimates[k * p + j] = solution.rank == static_cast<int>(p) ? solution.estimates[j] : kNaN;
      out.standard_errors[k * p + j] = solution.rank == static_cast<int>(p) ? solution.standard_errors[j] : kNaN;
    }
  }

  void fail(std::size_t piece, Diagnostic d) {
    std::lock_guard lock(problem_lock);
    if (!problem || piece < problem->first) problem.emplace(piece, std::move(d));
  }

  // Rows of sample s into (add) or out of (remove) the factor; false when a downdate was refused.
  static bool move_rows(RowCursor& cursor, SlidingFactor& f, std::size_t s, bool add, double& count) {
    const int p = f.columns();
    const std::span<const double> rows = cursor.rows_at(s);
    for (std::size_t at = 0; at < rows.size(); at += static_cast<std::size_t>(p + 1)) {
      const double* row = rows.data() + at;
      if (is_zero_row(row, p)) continue;
      if (add) {
        f.add(row, row[p]);
        count += 1;
      } else {
        if (!f.remove(row, row[p])) return false;
        count -= 1;
      }
    }
    return true;
  }

  void window_piece(std::size_t piece) {
    const int p = rows.p();
    const std::size_t k0 = piece * per_piece, k1 = std::min(windows, k0 + per_piece);
    const std::size_t last = k1 < windows ? k1 : k1 - 1;  // k1: the next piece's first window, for the border check
    auto in = cursor(rows), leaving = cursor(rows);
    SlidingFactor f(p);
    double count = 0;
    const SampledRecord& record = rows.one[0];
    auto start_fresh = [&](std::size_t k) {
      f.clear();
      count = 0;
      for (std::size_t s = k * S; s < k * S + W; ++s) move_rows(*in, f, s, true, count);
    };
    start_fresh(k0);
    ++fresh;
    for (std::size_t k = k0; k <= last; ++k) {
      if (k > k0) {
        if (S >= W) {
          start_fresh(k);
        } else {
          for (std::size_t s = (k - 1) * S + W; s < k * S + W; ++s) move_rows(*in, f, s, true, count);
          bool kept = true;
          for (std::size_t s = (k - 1) * S; s < k * S && kept; ++s) kept = move_rows(*leaving, f, s, false, count);
          if (!kept || f.residual_lost()) {
            ++refused;
            ++fresh;
            start_fresh(k);
          }
        }
      }
      if (auto d = in->problem()) return fail(piece, *d);
      if (auto d = leaving->problem()) return fail(piece, *d);
      const SlidingSolution solution = f.solve(count, tolerance);
      if (k == k1) {
        border[piece] = solution.estimates;
      } else {
        keep(solution, k, record.time[rows.window.first + k * S] + 0.5 * static_cast<double>(W - 1) * record.step, count);
      }
    }
  }

  void forgetting_piece(std::size_t piece) {
    const int p = rows.p();
    const double lambda = *local.forget, root = std::sqrt(lambda);
    const std::size_t k0 = piece * per_piece, k1 = std::min(windows, k0 + per_piece);
    const std::size_t last = k1 < windows ? k1 : k1 - 1;
    const std::size_t start = k0 * S > W ? k0 * S - W : 0;  // W: the warm-up
    auto in = cursor(rows);
    SlidingFactor f(p);
    const SampledRecord& record = rows.one[0];
    double count = 0, weight = 0, time = 0;
    for (std::size_t s = start; s <= last * S; ++s) {
      f.scale(root);
      count *= lambda;
      weight = lambda * weight + 1;
      time = lambda * time + record.time[rows.window.first + s];
      move_rows(*in, f, s, true, count);
      if (s % S != 0 || s < k0 * S) continue;
      if (auto d = in->problem()) return fail(piece, *d);
      const std::size_t k = s / S;
      const SlidingSolution solution = f.solve(count, tolerance);
      if (k == k1) border[piece] = solution.estimates;
      else keep(solution, k, time / weight, count);
    }
    ++fresh;
  }
};

std::string format_number(double v) { return fmt::format("{:.6g}", v); }

// The window's samples on `record` (at least one), or why WIDTH is longer than the `n` samples it
// may cover.
std::variant<std::size_t, Diagnostic> window_samples(const SampledRecord& record, double width, std::size_t n) {
  const double samples = std::round(width / record.step);
  if (!(samples <= static_cast<double>(n)))
    return diag::local_window_too_long(record.path, width, samples, n, static_cast<double>(n) * record.step);
  return static_cast<std::size_t>(std::max(samples, 1.0));
}

// A window of W samples holding at most `rows` rows (`per_sample` a sample on average) for p
// parameters: why it is too short, the least width named in the hint.
std::optional<Diagnostic> too_few_rows(const SampledRecord& record, double width, std::size_t W, std::size_t rows, std::size_t p,
                                       double per_sample) {
  if (rows >= p) return std::nullopt;
  return diag::local_window_too_short(record.path, width, W, rows, p, std::ceil(static_cast<double>(p) / per_sample) * record.step);
}

}  // namespace

std::optional<Diagnostic> check_local_window(const ir::Model& model, const std::vector<SampledRecord>& records, const LocalFitOptions& local,
                                             const FitOptions* options) {
  if (local.forget) return std::nullopt;
  for (const auto& record : records) {
    std::size_t n = record.time.size();
    if (options) {  // the fit window: the samples the derivatives leave, within --from/--to
      auto chosen = operators_for_record(options->evaluation, record, model);
      if (auto* d = std::get_if<Diagnostic>(&chosen)) return *d;
      auto window = fit_window(record, model, std::get<EvaluationOptions>(chosen), options->from, options->to);
      if (auto* d = std::get_if<Diagnostic>(&window)) return *d;
      n = std::get<FitWindow>(window).size();
    }
    auto samples = window_samples(record, local.width, n);
    if (auto* d = std::get_if<Diagnostic>(&samples)) return *d;
    const std::size_t W = std::get<std::size_t>(samples);
    const std::vector<SampledRecord> one{alone(record)};
    for (const auto& members : equation_groups(model)) {
      auto weak = is_weak_group(model, members);
      if (auto* d = std::get_if<Diagnostic>(&weak)) return *d;
      if (std::get<bool>(weak)) continue;  // rows are subdomains, known once chosen: local_fit() checks
      const std::size_t p = DesignBuilder(model, one, members).columns().size();
      if (auto d = too_few_rows(record, local.width, W, W * members.size(), p, static_cast<double>(members.size()))) return d;
    }
  }
  return std::nullopt;
}

std::variant<LocalFitSummary, Diagnostic> local_fit(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                    const FitOptions& options, const LocalFitOptions& local) {
  const auto clock = std::chrono::steady_clock::now();
  LocalFitSummary summary;
  summary.options = local;
  summary.threads = thread_count(options, local);
  // Each record's operators (its arcs under savgol(auto)) and fit window, for every group.
  std::vector<EvaluationOptions> evaluation;
  std::vector<FitWindow> windows;
  for (const auto& record : records) {
    auto chosen = operators_for_record(options.evaluation, record, model);
    if (auto* d = std::get_if<Diagnostic>(&chosen)) return *d;
    evaluation.push_back(std::get<EvaluationOptions>(std::move(chosen)));
    auto window = fit_window(record, model, evaluation.back(), options.from, options.to);
    if (auto* d = std::get_if<Diagnostic>(&window)) return *d;
    windows.push_back(std::get<FitWindow>(window));
  }
  const auto all_groups = equation_groups(model);
  for (const auto& members : all_groups) {
    LocalGroupFit group;
    group.equations = members;
    for (std::size_t r = 0; r < records.size(); ++r) {
      RowSource rows(model, records[r], members);
      rows.evaluation = evaluation[r];
      rows.window = windows[r];
      rows.design = std::make_unique<DesignBuilder>(model, rows.one, members);
      if (r == 0) {
        group.columns = rows.design->column_names();
        group.column_parameters = rows.design->column_indices();
      }
      auto weak = is_weak_group(model, members);
      if (auto* d = std::get_if<Diagnostic>(&weak)) return *d;
      if (std::get<bool>(weak)) {
        if (auto problem = prepare_weak_rows(rows)) return *problem;
      } else {
        std::vector<const ir::Sum*> sums = rows.design->sums();
        if (model.weights) sums.push_back(&model.weights->value);
        auto whole = prepare_whole_window_values(rows.one[0], model, rows.evaluation, rows.window, sums);
        if (auto* d = std::get_if<Diagnostic>(&whole)) return *d;
        rows.whole = std::get<WholeWindowValues>(std::move(whole));
      }

      const std::size_t n = rows.window.size(), p = static_cast<std::size_t>(rows.p());
      LocalRecordFit fit;
      fit.path = records[r].path;
      Slide slide{rows, local, options.least_squares.rank_tolerance, 0, std::max<std::size_t>(local.stride, 1), 0, 1, fit, {}, {}, {}, {}, {}};
      std::size_t span = 0;  // samples a piece must see before its first estimate
      if (local.forget) {
        const double lambda = *local.forget;
        // Rows this old weigh lambda^(age/2) <= 1e-16 in R (1e-32 in R^T R): below rounding.
        slide.W = static_cast<std::size_t>(std::ceil(std::log(1e-32) / std::log(lambda)));
        fit.window_samples = static_cast<std::size_t>(std::llround(1 / (1 - lambda)));
        slide.windows = (n - 1) / slide.S + 1;
        span = slide.W;
      } else {
        auto samples = window_samples(records[r], local.width, n);
        if (auto* d = std::get_if<Diagnostic>(&samples)) return *d;
        slide.W = std::get<std::size_t>(samples);
        // The most rows a window holds: every sample's equations, or the subdomains by centre.
        std::size_t most = slide.W * members.size();
        double per_sample = static_cast<double>(members.size());
        if (rows.weak) {
          most = 0;
          for (std::size_t s = 0; s + slide.W <= n; s += slide.W) most = std::max(most, rows.weak_first[s + slide.W] - rows.weak_first[s]);
          per_sample = static_cast<double>(rows.weak_first[n]) / static_cast<double>(n);
        }
        if (auto d = too_few_rows(records[r], local.width, slide.W, most, p, per_sample)) return *d;
        fit.window_samples = slide.W;
        slide.windows = (n - slide.W) / slide.S + 1;
        span = slide.W;
      }
      const std::size_t N = slide.windows;
      slide.per_piece = std::max<std::size_t>(1, (local.piece_turnovers * span + slide.S - 1) / slide.S);
      // At least kMostThreads pieces where the windows allow: the layout (and so the last digits,
      // which depend on where fresh factors start) is the same whatever the machine's cores.
      constexpr std::size_t kMostThreads = 8;
      const auto threads = static_cast<std::size_t>(summary.threads);
      if ((N + slide.per_piece - 1) / slide.per_piece < kMostThreads)
        slide.per_piece = std::max<std::size_t>(1, (N + kMostThreads - 1) / kMostThreads);
      const std::size_t pieces = (N + slide.per_piece - 1) / slide.per_piece;
      // Every window is written by exactly one piece (keep()).
      fit.t_center.resize(N);
      fit.G.resize(N);
      fit.n.resize(N);
      fit.rank.resize(N);
      fit.estimates.resize(N * p);
      fit.standard_errors.resize(N * p);
      slide.border.assign(pieces, {});

      const std::string label =
          all_groups.size() > 1 ? fmt::format("{}, equation group {}", records[r].path, summary.groups.size() + 1) : records[r].path;
      std::atomic<std::size_t> next{0}, done{0};
      auto work = [&](bool caller) {
        for (std::size_t piece = next++; piece < pieces; piece = next++) {
          if (local.forget) slide.forgetting_piece(piece);
          else slide.window_piece(piece);
          done += std::min(N, (piece + 1) * slide.per_piece) - piece * slide.per_piece;
          if (caller && local.progress) local.progress(label, done, N);
        }
      };
      std::vector<std::thread> running;
      for (std::size_t k = 1; k < std::min(threads, pieces); ++k) running.emplace_back(work, false);
      work(true);
      for (auto& t : running) t.join();
      if (local.progress) local.progress(label, N, N);
      if (slide.problem) return slide.problem->second;

      for (std::size_t piece = 0; piece + 1 < pieces; ++piece) {
        const std::size_t k = (piece + 1) * slide.per_piece;
        if (slide.border[piece].empty() || fit.rank[k] < static_cast<int>(p)) continue;
        double difference = 0, size = 0;
        for (std::size_t j = 0; j < p; ++j) {
          difference = std::max(difference, std::abs(slide.border[piece][j] - fit.estimates[k * p + j]));
          size = std::max(size, std::abs(fit.estimates[k * p + j]));
        }
        ++summary.drift_checks;
        if (size > 0) summary.max_drift = std::max(summary.max_drift, difference / size);
      }
      summary.fresh_factors += slide.fresh;
      summary.refused_downdates += slide.refused;
      summary.rank_deficient += static_cast<std::size_t>(std::count_if(fit.rank.begin(), fit.rank.end(), [&](int k) { return k < static_cast<int>(p); }));
      group.records.push_back(std::move(fit));
    }
    summary.groups.push_back(std::move(group));
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();
  return summary;
}

std::string LocalFitSummary::group_report(std::size_t group) const {
  std::string out;
  if (group >= groups.size()) return out;
  const LocalGroupFit& g = groups[group];
  const std::size_t p = g.columns.size();
  auto median = [](std::vector<double> v) {
    if (v.empty()) return kNaN;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  for (const auto& r : g.records) {
    const auto full = static_cast<std::size_t>(std::count(r.rank.begin(), r.rank.end(), static_cast<int>(p)));
    // Min and max over every window; medians over at most 10^5 of them, evenly spaced.
    const std::size_t every = std::max<std::size_t>(1, (r.windows() + 99'999) / 100'000);
    std::vector<double> low(p, kNaN), high(p, kNaN);
    std::vector<std::vector<double>> x(p), se(p);
    std::size_t without_se = 0;  // full rank, but n <= p: no residual degrees of freedom
    for (std::size_t k = 0; k < r.windows(); ++k) {
      if (r.rank[k] != static_cast<int>(p)) continue;
      if (p > 0 && !std::isfinite(r.standard_errors[k * p])) ++without_se;
      const double* e = &r.estimates[k * p];
      for (std::size_t j = 0; j < p; ++j) {
        low[j] = std::isnan(low[j]) ? e[j] : std::min(low[j], e[j]);
        high[j] = std::isnan(high[j]) ? e[j] : std::max(high[j], e[j]);
      }
      if (k % every != 0) continue;
      for (std::size_t j = 0; j < p; ++j) {
        x[j].push_back(e[j]);
        if (std::isfinite(r.standard_errors[k * p + j])) se[j].push_back(r.standard_errors[k * p + j]);
      }
    }
    out += fmt::format("{}: {} estimates ({} of full rank{}{}), {} {} samples\n", r.path, r.windows(), full,
                       without_se ? fmt::format(", {} of them without a standard error: n <= parameters", without_se) : std::string(),
                       every > 1 ? fmt::format("; medians of every {}th", every) : std::string(),
                       options.forget ? "a memory of about" : "windows of", r.window_samples);
    out += fmt::format("  {:<14} {:>12} {:>12} {:>12} {:>12}\n", "parameter", "min", "median", "max", "median SE");
    for (std::size_t j = 0; j < p; ++j) {
      if (std::isnan(low[j])) {
        out += fmt::format("  {:<14} (no window of full rank)\n", g.columns[j]);
        continue;
      }
      out += fmt::format("  {:<14} {:>12} {:>12} {:>12} {:>12}\n", g.columns[j], format_number(low[j]), format_number(median(x[j])),
                         format_number(high[j]), se[j].empty() ? std::string("-") : format_number(median(se[j])));
    }
  }
  return out;
}

std::string LocalFitSummary::report() const {
  std::string out;
  const std::string every = options.stride == 1 ? std::string("at every sample") : fmt::format("every {} samples", options.stride);
  if (options.forget)
    out += fmt::format("Local fits (thesis chapter V): exponential forgetting, lambda = {}, an estimate {}\n", format_number(*options.forget),
                       every);
  else
    out += fmt::format("Local fits (thesis chapter V): windows of {}, one {}\n", format_number(options.width), every);
  for (std::size_t g = 0; g < groups.size(); ++g) {
    std::string numbers;
    for (std::size_t e : groups[g].equations) numbers += (numbers.empty() ? "" : ", ") + std::to_string(e + 1);
    if (groups.size() > 1) out += fmt::format("  Equation{} {}\n", groups[g].equations.size() == 1 ? "" : "s", numbers);
    std::string table = group_report(g);
    for (std::size_t at = 0; at < table.size();) {
      const std::size_t end = table.find('\n', at);
      out += "  " + table.substr(at, end - at + 1);
      at = end + 1;
    }
  }
  out += fmt::format("  rank deficient: {} window{} (no estimate: `rank` below the parameters in local.csv)\n", rank_deficient,
                     rank_deficient == 1 ? "" : "s");
  out += fmt::format("  factors: {} fresh, {} downdate{} refused for loss of accuracy (refactored); updated against fresh at {} piece "
                     "border{}: largest relative difference of the estimates {:.2g}\n",
                     fresh_factors, refused_downdates, refused_downdates == 1 ? "" : "s", drift_checks, drift_checks == 1 ? "" : "s", max_drift);
  return out;
}

}  // namespace sidc
