#include "runtime/solve/weak_design.hpp"

#include <algorithm>
#include <cmath>
#include <list>
#include <map>
#include <mutex>
#include <set>

#include <fmt/format.h>

#include "diagnostics/data_catalogue.hpp"
#include "ir/traversal.hpp"
#include "runtime/operators/block_evaluator.hpp"
#include "runtime/operators/piecewise_inputs.hpp"
#include "runtime/parallel_ranges.hpp"
#include "runtime/solve/switch_quadrature.hpp"

namespace sidc {
namespace {

int highest_test_function_order(const DesignBuilder& design) {
  int k = 0;
  for (const ir::Sum* s : design.sums())
    ir::for_each_factor(*s, [&](const ir::Factor& f) {
      if (f.kind == ir::FactorKind::test_function) k = std::max(k, f.order);
    });
  return k;
}

// The outputs the group's equations use: their spectrum sets the subdomains' width.
std::set<std::string> outputs_used(const ir::Model& model, const DesignBuilder& design) {
  std::set<std::string> names;
  for (const ir::Sum* s : design.sums())
    ir::for_each_factor(*s, [&](const ir::Factor& f) {
      if (f.kind != ir::FactorKind::signal) return;
      const ir::Signal* signal = model.signal(f.name);
      if (signal && signal->kind == ir::Signal::Kind::output) names.insert(f.name);
    });
  return names;
}

ir::Sum signal_sum(const std::string& name) { return ir::factor(ir::Factor{ir::FactorKind::signal, name, 0, {}, {}, {}, {}}); }

// The order of a term's test function and the term without it (weak_pass puts exactly one, to the
// power 1, on every term; the compiled-model reader checks files for the same).
std::pair<int, ir::Term> split_test_function(const ir::Term& t) {
  ir::Term rest = t;
  int order = 0;
  auto it = std::find_if(rest.factors.begin(), rest.factors.end(), [](const auto& f) { return f.first.kind == ir::FactorKind::test_function; });
  if (it != rest.factors.end()) {
    order = it->first.order;
    rest.factors.erase(it);
  }
  return {order, rest};
}

}  // namespace

std::map<int, ir::Sum> parts_by_test_function(const ir::Sum& s) {
  std::map<int, std::vector<ir::Term>> terms;
  for (const auto& t : s.terms) {
    auto [k, rest] = split_test_function(t);
    terms[k].push_back(ir::canonical(rest));
  }
  std::map<int, ir::Sum> out;
  for (auto& [k, part] : terms) out[k] = ir::canonical(std::move(part));
  return out;
}

// sum_i a[i] * b[i] in four running sums, added pairwise at the end: one sum would wait on each
// addition in turn (a latency of four cycles per product); four keep the multiply-add units busy.
// The order is fixed, so the result is the same on every run and thread.
double running_dot(const double* a, const double* b, std::size_t n) {
  const std::size_t whole = n - n % 4;
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
  for (std::size_t i = 0; i < whole; i += 4) {
    s0 += a[i] * b[i];
    s1 += a[i + 1] * b[i + 1];
    s2 += a[i + 2] * b[i + 2];
    s3 += a[i + 3] * b[i + 3];
  }
  for (std::size_t i = whole; i < n; ++i) s0 += a[i] * b[i];
  return (s0 + s1) + (s2 + s3);
}

// Over a test function's support (thousands of samples).
double support_dot(const std::vector<double>& w, const double* x) { return running_dot(w.data(), x, w.size()); }

std::variant<bool, Diagnostic> is_weak_group(const ir::Model& model, const std::vector<std::size_t>& equations) {
  const auto weak = std::count_if(equations.begin(), equations.end(), [&](std::size_t e) { return model.equations[e].weak; });
  if (weak == 0 || weak == static_cast<std::ptrdiff_t>(equations.size())) return weak > 0;
  const std::size_t strong = *std::find_if(equations.begin(), equations.end(), [&](std::size_t e) { return !model.equations[e].weak; });
  return diag::weak_form_mixed(model.equations[strong].span);
}

WeakValues::WeakValues(Evaluator& evaluator, const TestFunctionGrid& grid, RowShare* share)
    : evaluator_(evaluator), grid_(grid), share_(share && share->parts() > 1 ? share : nullptr) {}

namespace {
// Window samples per block of WeakValues::add_rows.
constexpr std::size_t kWeakBlock = std::size_t{1} << 15;
}  // namespace

std::optional<Diagnostic> WeakValues::add_shared_rows(const ir::Sum& g, const std::string& what, const std::vector<double>& w,
                                                      std::span<double> out) {
  const std::size_t blocks = (evaluator_.window().size() + kWeakBlock - 1) / kWeakBlock;
  const auto [first, last] = RowShare::share_of(blocks, 1, share_->part(), share_->parts());
  std::vector<double> mine(out.size(), 0.0);
  const std::optional<Diagnostic> problem = add_rows(g, what, w, mine, first, last);
  const RowShare::Combined summed = share_->sum(mine, problem.has_value());
  if (summed.outcome == RowShare::Outcome::stopped) return diag::error("stopped", {}, summed.why);
  // A problem in some part's rows: every part integrates all rows, and so names the first problem
  // in the record's order, as one process does.
  if (summed.outcome == RowShare::Outcome::problem) return add_rows(g, what, w, out);
  for (std::size_t j = 0; j < out.size(); ++j) out[j] += mine[j];  // x + 0 + ... + 0: one part's value exactly
  return std::nullopt;
}

std::optional<Diagnostic> WeakValues::add_rows(const ir::Sum& g, const std::string& what, const std::vector<double>& w, std::span<double> out,
                                               std::size_t first_block, std::size_t last_block) {
  const FitWindow& window = evaluator_.window();
  const SampledRecord& record = evaluator_.record();
  const std::size_t n = window.size(), m = grid_.half_width, count = std::min(grid_.centres.size(), out.size());
  auto prepared = prepare_whole_window_values(record, evaluator_.model(), evaluator_.options(), window, {&g});
  if (auto* d = std::get_if<Diagnostic>(&prepared)) return *d;
  const WholeWindowValues& whole = std::get<WholeWindowValues>(prepared);
  // Window samples in blocks; row j belongs to the block its support's first sample c_j - m lies
  // in, and g is evaluated on the block and the 2m samples after it. A value that is not finite is
  // looked for on the block's own samples, and the first by term, then sample, is the one
  // Evaluator::evaluate_in_window names.
  const std::size_t blocks = (n + kWeakBlock - 1) / kWeakBlock;
  first_block = std::min(first_block, blocks);
  last_block = std::clamp(last_block, first_block, blocks);
  std::mutex found;
  std::optional<NonFiniteValue> first_bad;
  std::optional<Diagnostic> structural;  // a problem that is not a value (the same on every block)
  // Each row is its own dot product: the blocks split over the cores (at 10^7 samples, 8
  // subdomains cover each sample: about 8 * 10^7 products per column, the weak fit's largest cost).
  for_parallel_ranges(last_block - first_block, std::min(n, (last_block - first_block) * kWeakBlock) * w.size(), [&](std::size_t b0, std::size_t b1) {
    b0 += first_block;
    b1 += first_block;
    BlockEvaluator evaluator(record, evaluator_.options(), window, whole);
    std::vector<double> values;
    for (std::size_t b = b0; b < b1; ++b) {
      const std::size_t start = b * kWeakBlock, end = std::min(n, start + kWeakBlock), last = std::min(n, end + 2 * m);
      values.assign(last - start, 0.0);
      evaluator.start_block(window.first + start, window.first + last);
      std::optional<NonFiniteValue> bad;
      auto status = evaluator.evaluate(g, values, &bad);
      if (auto* d = std::get_if<Diagnostic>(&status)) {
        const std::lock_guard<std::mutex> lock(found);
        if (!structural) structural = std::move(*d);
        return;
      }
      if (bad && bad->sample < window.first + end) {
        const std::lock_guard<std::mutex> lock(found);
        if (!first_bad || std::pair{bad->term, bad->sample} < std::pair{first_bad->term, first_bad->sample}) first_bad = bad;
      }
      // Rows whose support starts in [start, end): c_j - m >= start, c_j - m < end.
      const auto from = std::lower_bound(grid_.centres.begin(), grid_.centres.begin() + static_cast<std::ptrdiff_t>(count), start + m);
      const auto to = std::lower_bound(from, grid_.centres.begin() + static_cast<std::ptrdiff_t>(count), end + m);
      for (auto it = from; it != to; ++it)
        out[static_cast<std::size_t>(it - grid_.centres.begin())] += support_dot(w, values.data() + (*it - m - start));
    }
  });
  if (structural) return structural;
  if (first_bad) return non_finite_value(record, g, *first_bad, what);
  return std::nullopt;
}

std::optional<Diagnostic> WeakValues::evaluate(const ir::Sum& sum, std::size_t, const std::string& what, std::span<double> out) {
  std::fill(out.begin(), out.end(), 0.0);
  const std::size_t m = grid_.half_width;
  for (const auto& [k, g_k] : parts_by_test_function(sum)) {
    if (weights_.size() <= static_cast<std::size_t>(k)) weights_.resize(static_cast<std::size_t>(k) + 1);
    auto& w = weights_[static_cast<std::size_t>(k)];
    if (w.empty()) w = test_function_weights(grid_, k, evaluator_.record().step);
    if (!evaluator_.segmented()) {
      if (auto problem = share_ ? add_shared_rows(g_k, what, w, out) : add_rows(g_k, what, w, out)) return problem;
      if (auto problem = add_switch_corrections(evaluator_, grid_, g_k, w, out)) return problem;
      continue;
    }
    // Held or linear inputs: int phi^(k) g interval by interval within the inputs' segments, g read
    // on its pieces (runtime/operators/piecewise_inputs.hpp); phi^(k) vanishes outside the support.
    auto stencil = evaluator_.stencil_values(g_k, &what);
    if (auto* d = std::get_if<Diagnostic>(&stencil)) return *d;
    const Evaluator::Stencil& g = std::get<Evaluator::Stencil>(stencil);  // g[o][a]: window sample a as interval a - d sees it
    const IntervalRules rules(0);
    const std::size_t first = evaluator_.window().first;
    for (std::size_t j = 0; j < grid_.centres.size() && j < out.size(); ++j) {
      const std::size_t start = grid_.centres[j] - m;  // window sample of the support's first node
      double total = 0;
      for (std::size_t i = 0; i + 1 < w.size(); ++i) {  // the support's 2m intervals
        const auto [lo, hi] = evaluator_.interval_nodes(first + start + i);
        const auto& rule = rules({lo, hi});
        for (int d = lo; d <= hi; ++d) {
          const auto r = static_cast<std::ptrdiff_t>(i) + d;  // node of the support (test function sample)
          if (r < 0 || r >= static_cast<std::ptrdiff_t>(w.size()) || w[static_cast<std::size_t>(r)] == 0.0) continue;
          const auto o = static_cast<std::size_t>(d - kPieceOffsets.front());
          total += rule[o] * w[static_cast<std::size_t>(r)] * g[o][start + static_cast<std::size_t>(r)];
        }
      }
      out[j] += total;
    }
  }
  return std::nullopt;
}

std::variant<WeakDesign, Diagnostic> weak_record_design(const ir::Model& model, const std::vector<SampledRecord>& records, std::size_t r,
                                                        Evaluator& evaluator, const DesignBuilder& design,
                                                        const std::vector<std::size_t>& equations, std::span<const double> expression,
                                                        RowShare* share, const TestFunctionGrid* given) {
  WeakDesign out;
  std::variant<TestFunctionGrid, Diagnostic> chosen = Diagnostic{};
  if (given) {
    chosen = *given;
  } else {
    // The outputs on the window, read where the record holds them (a copy is 80 MB each at 10^7
    // samples); an output the record lacks, or with a value that is not finite, is evaluated for
    // the evaluator's message.
    const FitWindow& fit_window = evaluator.window();
    std::vector<std::span<const double>> spans;
    std::list<std::vector<double>> evaluated;
    for (const auto& name : outputs_used(model, design)) {
      const auto found = records[r].signals.find(name);
      if (found != records[r].signals.end() && fit_window.first + fit_window.size() <= found->second.size()) {
        const auto v = std::span<const double>(found->second).subspan(fit_window.first, fit_window.size());
        if (std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); })) {
          spans.push_back(v);
          continue;
        }
      }
      auto v = evaluator.evaluate_in_window(signal_sum(name), "the output `" + name + "`");
      if (auto* d = std::get_if<Diagnostic>(&v)) return *d;
      spans.push_back(evaluated.emplace_back(std::get<std::vector<double>>(std::move(v))));
    }
    const std::size_t fewest_rows = std::max<std::size_t>(20, 4 * design.columns().size());
    chosen = choose_test_functions(spans, evaluator.window().size(), records[r].step, highest_test_function_order(design), fewest_rows,
                                   records[r].path);
  }
  if (auto* d = std::get_if<Diagnostic>(&chosen)) return *d;
  out.grids.push_back(std::get<TestFunctionGrid>(std::move(chosen)));
  const TestFunctionGrid& grid = out.grids.back();
  const FitWindow& w = evaluator.window();
  const auto K = static_cast<Eigen::Index>(grid.centres.size());
  const auto total = K * static_cast<Eigen::Index>(equations.size());
  out.A = Eigen::MatrixXd::Zero(total, static_cast<Eigen::Index>(design.columns().size()));
  out.b = Eigen::VectorXd::Zero(total);
  out.weights = Eigen::VectorXd::Ones(total);
  // eq. 2-1.6 on subdomains: each row's weight is the phi-weighted mean of its samples' weights.
  std::vector<double> products(expression.size());
  const double* sample_weight = design.row_weights(r, w.first, expression, products);
  Eigen::VectorXd row_weight = Eigen::VectorXd::Ones(K);
  if (sample_weight) {
    const std::vector<double> phi = test_function_weights(grid, 0, 1.0);
    double total_phi = 0;
    for (double v : phi) total_phi += v;
    for (Eigen::Index j = 0; j < K; ++j) {
      double s = 0;
      bool masked = false;  // a sample weighted 0 (an outlier, a dropout) takes out every subdomain it lies in
      for (std::size_t i = 0; i < phi.size(); ++i) {
        const double weight = sample_weight[grid.centres[static_cast<std::size_t>(j)] - grid.half_width + i];
        masked = masked || weight == 0.0;
        s += phi[i] * weight;
      }
      row_weight(j) = masked ? 0.0 : s / total_phi;
    }
  }
  WeakValues weak(evaluator, grid, share);
  Eigen::Index row = 0;
  for (std::size_t e : equations) {
    if (auto problem = design.equation_rows(r, e, weak, {out.A.middleRows(row, K), out.b.segment(row, K)})) return *problem;
    out.weights.segment(row, K) = row_weight;
    for (std::size_t c : grid.centres) {
      out.row_equation.push_back(e);
      out.row_record.push_back(r);
      out.row_time.push_back(records[r].time[w.first + c]);
    }
    row += K;
  }
  return out;
}

std::variant<WeakDesign, Diagnostic> weak_design(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                 std::vector<Evaluator>& evaluators, const DesignBuilder& design,
                                                 const std::vector<std::size_t>& equations,
                                                 const std::vector<std::vector<double>>& expression_weights, RowShare* share,
                                                 const std::vector<TestFunctionGrid>* given) {
  std::vector<WeakDesign> parts;
  Eigen::Index total = 0;
  for (std::size_t r = 0; r < records.size(); ++r) {
    const std::span<const double> expression = r < expression_weights.size() ? std::span<const double>(expression_weights[r]) : std::span<const double>();
    auto part = weak_record_design(model, records, r, evaluators[r], design, equations, expression, share,
                                   given && r < given->size() ? &(*given)[r] : nullptr);
    if (auto* d = std::get_if<Diagnostic>(&part)) return *d;
    parts.push_back(std::get<WeakDesign>(std::move(part)));
    total += parts.back().b.size();
  }
  WeakDesign out;
  out.A.resize(total, static_cast<Eigen::Index>(design.columns().size()));
  out.b.resize(total);
  out.weights.resize(total);
  Eigen::Index row = 0;
  for (auto& part : parts) {
    const Eigen::Index n = part.b.size();
    out.A.middleRows(row, n) = part.A;
    out.b.segment(row, n) = part.b;
    out.weights.segment(row, n) = part.weights;
    out.row_equation.insert(out.row_equation.end(), part.row_equation.begin(), part.row_equation.end());
    out.row_record.insert(out.row_record.end(), part.row_record.begin(), part.row_record.end());
    out.row_time.insert(out.row_time.end(), part.row_time.begin(), part.row_time.end());
    out.grids.push_back(std::move(part.grids.front()));
    row += n;
  }
  return out;
}

std::string describe(const TestFunctionGrid& grid, double step) {
  return fmt::format("{} subdomains of 2*{}+1 samples (half-width {:.4g}), phi = (1 - s^2)^{}; {}", grid.centres.size(), grid.half_width,
                     static_cast<double>(grid.half_width) * step, grid.degree, grid.reason);
}

}  // namespace sidc
