// Integrals carried stretch by stretch (see running_integrals.hpp). The rules are simpson.cpp's,
// written out again sample by sample; keep the two in step.
#include "runtime/operators/running_integrals.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <thread>

#include "diagnostics/data_catalogue.hpp"
#include "ir/print.hpp"
#include "ir/traversal.hpp"
#include "runtime/not_a_number.hpp"
#include "runtime/operators/piecewise_inputs.hpp"

namespace sidc {
namespace {

using ir::FactorKind;

bool is_integral(const ir::Factor& f) { return f.kind == FactorKind::integral; }

// 0 for a sum without integrals; 1 + the deepest integral inside otherwise.
int integral_depth(const ir::Sum& s) {
  int depth = 0;
  ir::walk_factors(s, [&](const ir::Factor& f, const ir::Term&) {
    if (!is_integral(f)) return ir::Step::into;
    depth = std::max(depth, 1 + integral_depth(*f.argument));
    return ir::Step::over;
  });
  return depth;
}

}  // namespace

bool RunningIntegrals::carries(const ir::Model& model, const EvaluationOptions& options, FitWindow window,
                               const std::vector<const ir::Sum*>& sums) {
  const bool any = std::any_of(sums.begin(), sums.end(), [](const ir::Sum* s) { return ir::any_factor(*s, is_integral); });
  if (!any || options.integration.smoothing_window != 0 || has_piecewise_inputs(model) || window.size() < 4) return false;
  if (model.weights && ir::any_factor(model.weights->value, is_integral)) return false;
  // A derivative of an integral reads beyond the block it is asked for, hence beyond a stretch.
  return std::none_of(sums.begin(), sums.end(), [](const ir::Sum* s) {
    return ir::any_factor(*s, [](const ir::Factor& f) { return f.kind == FactorKind::derivative && ir::any_factor(*f.argument, is_integral); });
  });
}

std::variant<RunningIntegrals, Diagnostic> RunningIntegrals::start(const SampledRecord& record, const ir::Model& model,
                                                                   const EvaluationOptions& options, FitWindow window,
                                                                   const std::vector<const ir::Sum*>& sums) {
  if (!carries(model, options, window, sums)) {
    auto prepared = prepare_whole_window_values(record, model, options, window, sums);
    if (auto* d = std::get_if<Diagnostic>(&prepared)) return std::move(*d);
    RunningIntegrals whole(record, options, window);
    whole.values_ = std::get<WholeWindowValues>(std::move(prepared));
    whole.prepared_whole_ = true;
    return whole;
  }
  // cumulative_integral()'s own check, so that the message is the one the whole window would give.
  if (!(record.step > 0) || !std::isfinite(record.step))
    return data_diag::invalid_signal_options("an integral", "the sample spacing must be a positive number");
  RunningIntegrals running(record, options, window);
  std::optional<Evaluator> evaluator;  // only for initial values, and only when there are some
  std::optional<Diagnostic> error;
  for (const ir::Sum* s : sums) {
    ir::walk_factors(*s, [&](const ir::Factor& f, const ir::Term& t) {
      const std::string key = print(f);
      if (is_integral(f)) {
        if (!running.values_.integrals.count(key)) {
          running.values_.integrals[key];
          Carried c;
          c.key = key;
          c.integrand = &*f.argument;
          c.depth = 1 + integral_depth(*f.argument);
          running.carried_.push_back(std::move(c));
        }
      } else if (f.kind == FactorKind::initial_value && !running.values_.initial_values.count(key)) {
        if (!evaluator) evaluator.emplace(record, model, options, window);
        auto values = evaluator->evaluate(ir::factor(f, 1, t.span));  // 0 + 1 * value: the value itself
        if (auto* d = std::get_if<Diagnostic>(&values)) {
          error = std::move(*d);
          return ir::Step::stop;
        }
        const auto& v = std::get<std::vector<double>>(values);
        running.values_.initial_values[key] = v.empty() ? kNaN : v.front();
      }
      return ir::Step::into;  // integrands and guards hold integrals and initial values too
    });
    if (error) return *error;
  }
  std::stable_sort(running.carried_.begin(), running.carried_.end(),
                   [](const Carried& a, const Carried& b) { return a.depth < b.depth; });
  return running;
}

std::size_t RunningIntegrals::stretch_rows(std::size_t asked) const {
  return prepared_whole_ ? window_.size() : std::max<std::size_t>(asked, 4);
}

void RunningIntegrals::restart() {
  done_ = 0;
  for (auto& c : carried_) {
    c.even = c.last = 0;
    std::fill(std::begin(c.history), std::end(c.history), 0.0);
  }
}

std::optional<Diagnostic> RunningIntegrals::advance(std::size_t last, int threads, std::size_t block_rows) {
  const std::size_t first = done_;
  if (last < first || last > window_.size() || (!prepared_whole_ && first == 0 && last < 4 && last != 0))
    throw std::logic_error("RunningIntegrals::advance: not the next stretch of the window");
  if (last == first || prepared_whole_) {
    done_ = last;
    return std::nullopt;
  }
  values_.integrals_first = window_.first + first;
  for (auto& c : carried_) {
    c.integrand_values.resize(last - first);
    values_.integrals[c.key].resize(last - first);
  }
  const int deepest = carried_.empty() ? 0 : carried_.back().depth;
  for (int depth = 1; depth <= deepest; ++depth) {
    if (auto problem = evaluate_integrands(depth, first, last, threads, block_rows)) return problem;
    for (auto& c : carried_)
      if (c.depth == depth) carry(c, first, last);
  }
  done_ = last;
  return std::nullopt;
}

// The integrands of one depth on window samples [first, last), in contiguous parts, one per thread,
// each read by its own block evaluator (the deeper integrals' values on this stretch are ready).
std::optional<Diagnostic> RunningIntegrals::evaluate_integrands(int depth, std::size_t first, std::size_t last, int threads,
                                                                std::size_t block_rows) {
  block_rows = std::max<std::size_t>(block_rows, 1);
  const std::size_t n = last - first;
  const std::size_t parts = std::clamp<std::size_t>(n / (4 * block_rows), 1, static_cast<std::size_t>(std::max(threads, 1)));
  std::vector<std::optional<Diagnostic>> problems(parts);
  const auto evaluate_part = [&](std::size_t k) {
    BlockEvaluator evaluator(*record_, options_, window_, values_);
    const std::size_t begin = first + n * k / parts, end = first + n * (k + 1) / parts;
    for (std::size_t start = begin; start < end; start += block_rows) {
      const std::size_t stop = std::min(end, start + block_rows);
      evaluator.start_block(window_.first + start, window_.first + stop);
      for (auto& c : carried_) {
        if (c.depth != depth) continue;
        auto status = evaluator.evaluate(*c.integrand, std::span<double>(c.integrand_values.data() + (start - first), stop - start));
        if (auto* d = std::get_if<Diagnostic>(&status)) {
          problems[k] = std::move(*d);
          return;
        }
      }
    }
  };
  std::vector<std::thread> running;
  for (std::size_t k = 1; k < parts; ++k) running.emplace_back(evaluate_part, k);
  evaluate_part(0);
  for (auto& t : running) t.join();
  for (auto& p : problems)
    if (p) return p;
  return std::nullopt;
}

// simpson.cpp's cumulative rules from where the last stretch ended; i counts window samples.
void RunningIntegrals::carry(Carried& c, std::size_t first, std::size_t last) {
  const double h = record_->step;
  const std::vector<double>& values = c.integrand_values;
  const auto f = [&](std::size_t i) { return i >= first ? values[i - first] : c.history[3 - (first - i)]; };
  std::vector<double>& out = values_.integrals[c.key];
  if (options_.integration.rule == IntegrationOptions::Rule::trapezoid) {
    for (std::size_t i = first; i < last; ++i) {
      c.last = i == 0 ? 0.0 : c.last + h / 2 * (f(i - 1) + f(i));
      out[i - first] = c.last;
    }
  } else {
    for (std::size_t i = first; i < last; ++i) {
      double v;
      if (i == 0) {
        v = c.even = 0.0;
      } else if (i % 2 == 0) {
        v = c.even = c.even + h / 3 * (f(i - 2) + 4 * f(i - 1) + f(i));  // composite Simpson (section 3-2)
      } else if (i == 1) {
        v = h / 24 * (9 * f(0) + 19 * f(1) - 5 * f(2) + f(3));  // the cubic through the first four samples
      } else {
        v = c.even + h / 24 * (f(i - 3) - 5 * f(i - 2) + 19 * f(i - 1) + 9 * f(i));
      }
      out[i - first] = v;
    }
  }
  const double kept[3] = {f(last - 3), f(last - 2), f(last - 1)};  // last >= 4 (advance)
  std::copy(kept, kept + 3, c.history);
}

}  // namespace sidc
