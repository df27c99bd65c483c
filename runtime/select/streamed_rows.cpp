// select's rows of one record, streamed (see streamed_rows.hpp).
#include "runtime/select/streamed_rows.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <thread>

#include "ir/traversal.hpp"
#include "runtime/operators/block_evaluator.hpp"
#include "runtime/operators/running_integrals.hpp"
#include "runtime/select/size_rule.hpp"

namespace sidc {
namespace {

// A block's values; any problem (structural, or a value that is not finite) only marks the pass,
// which then gives the record back to the whole rows.
class MarkingValues final : public DesignValues {
 public:
  MarkingValues(BlockEvaluator& evaluator, bool& failed) : evaluator_(evaluator), failed_(failed) {}
  std::optional<Diagnostic> evaluate(const ir::Sum& sum, std::size_t, const std::string&, std::span<double> out) override {
    std::optional<NonFiniteValue> bad;
    auto status = evaluator_.evaluate(sum, out, &bad);
    if (auto* d = std::get_if<Diagnostic>(&status)) {
      failed_ = true;
      return std::move(*d);
    }
    if (bad) {
      failed_ = true;
      return Diagnostic{};
    }
    return std::nullopt;
  }

 private:
  BlockEvaluator& evaluator_;
  bool& failed_;
};

// One thread's share: its own triangles (one per time block) and, per stretch, its piece's line sums.
struct Worker {
  std::vector<TriangularAccumulator> blocks;
  std::vector<LineShareSums> lines;
  bool failed = false;
};

// One process's pieces of a record as one state: per triangle and per line piece, its length and
// its own state (TriangularAccumulator and LineShareSums to_doubles).
std::vector<double> pack_pieces(const std::vector<TriangularAccumulator>& triangles, const std::vector<LineShareSums>& lines) {
  std::vector<double> out;
  const auto put = [&out](const std::vector<double>& piece) {
    out.push_back(static_cast<double>(piece.size()));
    out.insert(out.end(), piece.begin(), piece.end());
  };
  for (const auto& t : triangles) put(t.to_doubles());
  for (const auto& l : lines) put(l.to_doubles());
  return out;
}

bool unpack_pieces(const std::vector<double>& state, std::vector<TriangularAccumulator>& triangles, std::vector<LineShareSums>& lines) {
  std::size_t at = 0;
  const auto get = [&](std::vector<double>& piece) {
    if (at >= state.size()) return false;
    const auto length = static_cast<std::size_t>(state[at++]);
    if (length > state.size() - at) return false;
    piece.assign(state.begin() + static_cast<std::ptrdiff_t>(at), state.begin() + static_cast<std::ptrdiff_t>(at + length));
    at += length;
    return true;
  };
  std::vector<double> piece;
  for (auto& t : triangles)
    if (!get(piece) || !t.from_doubles(piece)) return false;
  for (auto& l : lines)
    if (!get(piece) || !l.from_doubles(piece)) return false;
  return at == state.size();
}

// The record's pieces of every process, merged (true), or some process failed (false: every
// process then builds the record's rows whole), or the job stopped (a Diagnostic).
std::variant<bool, Diagnostic> merge_record_pieces(RowShare& share, std::vector<TriangularAccumulator>& triangles,
                                                   std::vector<LineShareSums>& lines, int p, bool failed) {
  std::vector<double> state = pack_pieces(triangles, lines);
  const std::vector<LineShareSums> shape = lines;  // the right number and shape of line pieces
  const RowShare::Merge merge = [&](std::vector<double>& left, const std::vector<double>& right) {
    std::vector<TriangularAccumulator> a(triangles.size(), TriangularAccumulator(p)), b = a;
    std::vector<LineShareSums> la = shape, lb = shape;
    if (!unpack_pieces(left, a, la) || !unpack_pieces(right, b, lb)) return;  // cannot happen: the same shapes everywhere
    for (std::size_t k = 0; k < a.size(); ++k) a[k].merge(b[k]);
    for (std::size_t k = 0; k < la.size(); ++k) la[k].join(lb[k]);
    left = pack_pieces(a, la);
  };
  const RowShare::Combined combined = share.merge(state, merge, failed);
  if (combined.outcome == RowShare::Outcome::stopped) return diag::error("stopped", {}, combined.why);
  if (combined.outcome == RowShare::Outcome::problem) return false;
  return unpack_pieces(state, triangles, lines);
}

}  // namespace

std::variant<StreamedRows, Diagnostic> stream_record_rows(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                          std::size_t r, const EvaluationOptions& evaluation, FitWindow window,
                                                          const DesignBuilder& design, const std::vector<std::size_t>& members,
                                                          const FitOptions& options, std::vector<TriangularAccumulator>& blocks,
                                                          std::vector<std::vector<double>>& shares) {
  const SampledRecord& record = records[r];
  const auto p = static_cast<Eigen::Index>(design.columns().size());
  const std::size_t W = window.size(), E = members.size(), F = blocks.size();
  std::vector<const ir::Sum*> sums = design.sums();
  if (model.weights) sums.push_back(&model.weights->value);

  // Integrals carried, or (where they cannot be) the whole window's prepared at once.
  auto started = RunningIntegrals::start(record, model, evaluation, window, sums);
  if (auto* d = std::get_if<Diagnostic>(&started)) return *d;
  RunningIntegrals& running = std::get<RunningIntegrals>(started);

  const int threads = stream_thread_count(options);
  const std::size_t block_rows = std::max<std::size_t>(options.stream_block_rows, 1);
  std::vector<Worker> workers(static_cast<std::size_t>(threads));
  for (auto& w : workers) w.blocks.assign(F, TriangularAccumulator(static_cast<int>(p)));
  std::vector<LineShareSums> lines;
  for (std::size_t k = 0; k < E; ++k) lines.emplace_back(W, p, model.equations[members[k]].integrations);
  const bool weighted = !record.weights.empty() || model.weights;

  // Window rows [begin, end) into one worker: chunks of at most block_rows that never cross a time
  // block, each equation's rows evaluated, checked, interleaved as the whole design folds them
  // (sample i, equation k at row i E + k) and folded into its time block's triangle.
  const auto fold_part = [&](const WholeWindowValues& values, Worker& worker, std::size_t begin, std::size_t end) {
    BlockEvaluator evaluator(record, evaluation, window, values);
    MarkingValues marking(evaluator, worker.failed);
    // With several equations, each one's rows first apart, then interleaved into the fold's area.
    std::vector<Eigen::MatrixXd> A(E > 1 ? E : 0, Eigen::MatrixXd(static_cast<Eigen::Index>(block_rows), p));
    std::vector<Eigen::VectorXd> b(E > 1 ? E : 0, Eigen::VectorXd(static_cast<Eigen::Index>(block_rows)));
    std::vector<double> expression(model.weights ? block_rows : 0), products(block_rows), row_weights(block_rows * E);
    for (std::size_t start = begin; start < end && !worker.failed;) {
      std::size_t tb = start * F / W;  // the time block holding `start`
      while (W * (tb + 1) / F <= start) ++tb;
      while (tb > 0 && W * tb / F > start) --tb;
      const std::size_t stop = std::min({end, start + block_rows, W * (tb + 1) / F});
      const std::size_t m = stop - start, first = window.first + start;
      const auto mi = static_cast<Eigen::Index>(m);
      evaluator.start_block(first, stop + window.first);
      std::span<const double> expression_values;
      if (model.weights) {
        auto status = evaluator.evaluate(model.weights->value, std::span<double>(expression.data(), m));
        if (std::holds_alternative<Diagnostic>(status) ||
            check_weights(model, record, std::span<const double>(expression.data(), m), first)) {
          worker.failed = true;
          return;
        }
        expression_values = std::span<const double>(expression.data(), m);
      }
      const double* w = design.row_weights(r, first, expression_values, products);
      TriangularAccumulator& triangle = worker.blocks[tb];
      auto area = triangle.rows_area(mi * static_cast<Eigen::Index>(E));  // [A b], folded in place
      area.setZero();
      if (E == 1) {
        if (design.equation_rows(r, members[0], marking, {area.leftCols(p), area.col(p)}) || worker.failed) {
          worker.failed = true;
          return;
        }
        worker.lines[0].add(start, area.leftCols(p));  // before the weights
      } else {
        for (std::size_t k = 0; k < E; ++k) {
          A[k].topRows(mi).setZero();
          if (design.equation_rows(r, members[k], marking, {A[k].topRows(mi), b[k].head(mi)}) || worker.failed) {
            worker.failed = true;
            return;
          }
          worker.lines[k].add(start, A[k].topRows(mi));
          for (std::size_t i = 0; i < m; ++i) {
            const auto to = static_cast<Eigen::Index>(i * E + k), from = static_cast<Eigen::Index>(i);
            area.row(to).head(p) = A[k].row(from);
            area(to, p) = b[k](from);
          }
        }
      }
      const double* fold_weights = nullptr;
      if (weighted) {
        for (std::size_t i = 0; i < m; ++i)
          for (std::size_t k = 0; k < E; ++k) row_weights[i * E + k] = w ? w[i] : 1.0;
        fold_weights = row_weights.data();
      }
      if (!triangle.fold_rows_area(mi * static_cast<Eigen::Index>(E), fold_weights)) {
        worker.failed = true;
        return;
      }
      start = stop;
    }
  };

  // Shared among processes (FitOptions::share): this one folds window rows [mine_first, mine_last)
  // only, its integrals carried from the window's start as far as its share needs them.
  RowShare* share = options.share && options.share->parts() > 1 ? options.share : nullptr;
  const auto [mine_first, mine_last] =
      share ? RowShare::share_of(W, block_rows, share->part(), share->parts()) : std::pair<std::size_t, std::size_t>{0, W};
  bool failed = false;
  const std::size_t stretch = running.stretch_rows(options.stream_stretch_rows);
  for (std::size_t stretch_first = 0; stretch_first < mine_last && !failed; stretch_first += stretch) {
    const std::size_t end = std::min(mine_last, stretch_first + stretch);
    if (running.advance(end, threads, block_rows)) {
      failed = true;
      break;
    }
    if (end <= mine_first) continue;
    const std::size_t begin = std::max(stretch_first, mine_first);
    const WholeWindowValues& values = running.values();
    const std::size_t chunks = (end - begin + block_rows - 1) / block_rows;
    const std::size_t parts = std::min<std::size_t>(static_cast<std::size_t>(threads), std::max<std::size_t>(chunks / 4, 1));
    const auto bound = [&](std::size_t k) { return std::min(end, begin + chunks * k / parts * block_rows); };
    for (std::size_t k = 0; k < parts; ++k) {
      workers[k].lines.clear();
      for (std::size_t e = 0; e < E; ++e) workers[k].lines.emplace_back(W, p, model.equations[members[e]].integrations);
    }
    std::vector<std::thread> pool;
    for (std::size_t k = 1; k < parts; ++k) pool.emplace_back([&, k] { fold_part(values, workers[k], bound(k), bound(k + 1)); });
    fold_part(values, workers[0], begin, bound(1));
    for (auto& t : pool) t.join();
    for (std::size_t k = 0; k < parts && !failed; ++k) {
      failed = workers[k].failed;
      for (std::size_t e = 0; e < E && !failed; ++e) lines[e].join(workers[k].lines[e]);
    }
  }
  if (failed && !share) return StreamedRows::use_whole_rows;
  if (!share) {
    for (const auto& w : workers)
      for (std::size_t b = 0; b < F; ++b) blocks[b].merge(w.blocks[b]);
  } else {
    // This record's triangles apart from `blocks` (which may hold earlier records' rows): every
    // process's merged and line pieces joined in process order (each piece's rows come right after
    // the last one's); a problem anywhere sends every process to the whole rows.
    std::vector<TriangularAccumulator> mine(F, TriangularAccumulator(static_cast<int>(p)));
    for (const auto& w : workers)
      for (std::size_t b = 0; b < F; ++b) mine[b].merge(w.blocks[b]);
    auto merged = merge_record_pieces(*share, mine, lines, static_cast<int>(p), failed);
    if (auto* d = std::get_if<Diagnostic>(&merged)) return *d;
    if (!std::get<bool>(merged)) return StreamedRows::use_whole_rows;
    for (std::size_t b = 0; b < F; ++b) blocks[b].merge(mine[b]);
  }
  shares.clear();
  for (const auto& l : lines) shares.push_back(l.shares());
  return StreamedRows::folded;
}

}  // namespace sidc
