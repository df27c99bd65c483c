#include "runtime/operators/evaluate.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <fmt/format.h>

#include "ir/queries.hpp"
#include "ir/print.hpp"
#include "ir/traversal.hpp"
#include "diagnostics/data_catalogue.hpp"
#include "runtime/operators/piecewise_inputs.hpp"
#include "runtime/not_a_number.hpp"
#include "runtime/parallel_ranges.hpp"
#include <stdexcept>

namespace sidc {
namespace {

using ir::FactorKind;

std::size_t index_at_or_after(std::span<const double> time, double t) {
  const double tolerance = 1e-9 * std::max(1.0, std::abs(t));
  return static_cast<std::size_t>(std::lower_bound(time.begin(), time.end(), t - tolerance) - time.begin());
}

}  // namespace

void apply_condition(ir::Relation relation, std::span<const double> lhs, std::span<const double> rhs, std::span<double> guard) {
  for (std::size_t i = 0; i < guard.size(); ++i) {
    if (std::isnan(lhs[i]) || std::isnan(rhs[i])) {
      guard[i] = kNaN;
      continue;
    }
    const bool holds = relation == ir::Relation::less ? lhs[i] < rhs[i]
                     : relation == ir::Relation::less_equal ? lhs[i] <= rhs[i]
                     : relation == ir::Relation::greater ? lhs[i] > rhs[i] : lhs[i] >= rhs[i];
    if (!holds) guard[i] = 0.0;
  }
}

void apply_function(const std::string& name, std::span<double> values) {
  // A loop per function rather than a name comparison per sample (std:: functions may not be
  // taken by address, so each gets its own loop).
  auto each = [&](auto f) {
    for (double& x : values) x = f(x);
  };
  if (name == "sin") each([](double x) { return std::sin(x); });
  else if (name == "cos") each([](double x) { return std::cos(x); });
  else if (name == "exp") each([](double x) { return std::exp(x); });
  else if (name == "log") each([](double x) { return std::log(x); });
  else if (name == "sqrt") each([](double x) { return std::sqrt(x); });
  else if (name == "abs") each([](double x) { return std::abs(x); });
  else if (name == "tanh") each([](double x) { return std::tanh(x); });
  else each([](double x) { return std::isnan(x) ? x : static_cast<double>((x > 0) - (x < 0)); });  // sign
}

int highest_derivative_order(const ir::Model& model) {
  int k = 0;
  for (const auto& e : model.equations) k = std::max(k, derivative_burden(e));
  return k;
}

DerivativeOptions derivative_options_for(const EvaluationOptions& options, const std::string& signal, int order) {
  if (!options.automatic_derivative || order == 0) return options.derivative;
  if (auto s = options.chosen.find(signal); s != options.chosen.end())
    if (auto o = s->second.find(order); o != s->second.end()) return o->second;
  throw std::logic_error(fmt::format("no moving arc was chosen for derivative {} of `{}` (operators_for_record() not applied)", order, signal));
}

namespace {

// What one sum loses at each edge under savgol(auto): a derivative its own arc's half-window
// (its arcs' for a repeated one), a der() that plus what its argument loses already.
int samples_lost_by(const ir::Sum& s, const EvaluationOptions& options) {
  int lost = 0;
  for (const auto& t : s.terms)
    for (const auto& [f, power] : t.factors) {
      int here = 0;
      switch (f.kind) {
        case FactorKind::signal:
        case FactorKind::initial_value:
          if (f.order > 0) here = samples_lost_each_side(f.order, derivative_options_for(options, f.name, f.order));
          break;
        case FactorKind::derivative:
          here = samples_lost_by(*f.argument, options) + samples_lost_each_side(f.order, derivative_options_for(options, print(f), f.order));
          break;
        case FactorKind::function:
        case FactorKind::power:
        case FactorKind::integral: here = samples_lost_by(*f.argument, options); break;
        case FactorKind::guard:
          for (const auto& c : f.conditions) here = std::max({here, samples_lost_by(*c.lhs, options), samples_lost_by(*c.rhs, options)});
          break;
        case FactorKind::time:
        case FactorKind::elapsed:
        case FactorKind::window_start:
        case FactorKind::parameter:
        case FactorKind::test_function: break;  // known exactly: nothing lost
      }
      lost = std::max(lost, here);
    }
  return lost;
}

}  // namespace

int samples_lost_by_model(const ir::Model& model, const EvaluationOptions& options) {
  if (!options.automatic_derivative) {  // one arc for all: the highest order decides (eq. 4-1.10)
    const int order = highest_derivative_order(model);
    return order > 0 ? samples_lost_each_side(order, options.derivative) : 0;
  }
  int lost = 0;
  for (const auto& e : model.equations) {
    lost = std::max(lost, samples_lost_by(e.known, options));
    for (const auto& p : e.terms) lost = std::max(lost, samples_lost_by(p.operation, options));
  }
  return lost;
}

std::variant<FitWindow, Diagnostic> fit_window(const SampledRecord& record, const ir::Model& model,
                                               const EvaluationOptions& options, std::optional<double> from,
                                               std::optional<double> to) {
  const std::size_t n = record.time.size();
  const int order = highest_derivative_order(model);
  const std::size_t margin = static_cast<std::size_t>(std::max(0, samples_lost_by_model(model, options)));
  FitWindow w;
  w.first = margin;
  w.last = n > margin ? n - 1 - margin : 0;
  if (from) w.first = std::max(w.first, index_at_or_after(record.time, *from));
  if (to) {  // the last sample at or before `to` (0.82 itself when it is a sample)
    const double tolerance = 1e-9 * std::max(1.0, std::abs(*to));
    const auto past = static_cast<std::size_t>(std::upper_bound(record.time.begin(), record.time.end(), *to + tolerance) - record.time.begin());
    if (past == 0) w.last = 0, w.first = 1;
    else w.last = std::min(w.last, past - 1);
  }
  if (n <= 2 * margin || w.first > w.last) {
    return data_diag::empty_fit_window(record.path, n, order, margin, from || to);
  }
  return w;
}

Evaluator::Evaluator(const SampledRecord& record, const ir::Model& model, const EvaluationOptions& options, FitWindow window)
    : record_(record), model_(model), options_(options), window_(window), segmented_(has_piecewise_inputs(model)) {}

std::variant<std::vector<double>, Diagnostic> Evaluator::signal(const std::string& name, int order, const Span& where) {
  auto view = signal_view(name, order, where);
  if (auto* d = std::get_if<Diagnostic>(&view)) return *d;
  const std::span<const double> values = std::get<std::span<const double>>(view);
  return Values(values.begin(), values.end());
}

std::variant<std::span<const double>, Diagnostic> Evaluator::signal_view(const std::string& name, int order, const Span& where) {
  const auto key = std::pair{name, order};
  if (auto it = derivatives_.find(key); it != derivatives_.end()) return std::span<const double>(it->second);
  const auto found = record_.signals.find(name);
  if (found == record_.signals.end()) {
    return diag::signal_not_in_record(where, name, record_.path);
  }
  // The recorded samples themselves: a copy would be 80 MB more at 10^7 samples.
  if (order == 0) return std::span<const double>(found->second);
  auto estimate = derivative_operator(options_, order, name)->apply(found->second, record_.step);
  if (auto* d = std::get_if<Diagnostic>(&estimate)) return *d;
  return std::span<const double>(derivatives_[key] = std::get<Values>(std::move(estimate)));
}

std::variant<std::span<const double>, Diagnostic> Evaluator::factor_view(const ir::Factor& f, const Span& where, Values& scratch) {
  if (f.kind == FactorKind::signal) {
    return signal_view(f.name, f.order, where);
  }
  if (f.kind == FactorKind::derivative || f.kind == FactorKind::integral) {
    const std::string key = print(f);
    if (composite_.find(key) == composite_.end()) {  // factor() makes and keeps it
      auto made = factor(f, where);
      if (auto* d = std::get_if<Diagnostic>(&made)) return *d;
    }
    return std::span<const double>(composite_.at(key));
  }
  auto made = factor(f, where);
  if (auto* d = std::get_if<Diagnostic>(&made)) return *d;
  scratch = std::get<Values>(std::move(made));
  return std::span<const double>(scratch);
}

std::variant<double, Diagnostic> Evaluator::initial_value(const ir::Factor& f, const Span& where) {
  const auto& time = record_.time;
  std::size_t index = window_.first;
  const std::string text = print(f);
  if (f.at) {
    const double t = f.at->value();
    if (t < time.front() - 1e-9 || t > time.back() + 1e-9)
      return diag::initial_value_outside_record(where, text, t, time.front(), time.back());
    index = std::min(index_at_or_after(time, t), time.size() - 1);
    auto values = signal(f.name, f.order, where);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    const auto& v = std::get<Values>(values);
    // Between two samples: linear interpolation.
    if (index > 0 && std::abs(time[index] - t) > 1e-9 * std::max(1.0, std::abs(t))) {
      const double a = (t - time[index - 1]) / (time[index] - time[index - 1]);
      const double value = (1 - a) * v[index - 1] + a * v[index];
      if (!std::isfinite(value)) return diag::initial_value_unavailable(where, text, t, record_.path);
      return value;
    }
    if (!std::isfinite(v[index])) return diag::initial_value_unavailable(where, text, t, record_.path);
    return v[index];
  }
  auto values = signal(f.name, f.order, where);
  if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
  const double value = std::get<Values>(values)[index];
  if (!std::isfinite(value)) return diag::initial_value_unavailable(where, text, time[index], record_.path);
  return value;
}

std::variant<std::vector<double>, Diagnostic> Evaluator::factor(const ir::Factor& f, const Span& where) {
  const std::size_t n = record_.time.size();
  switch (f.kind) {
    case FactorKind::signal: return signal(f.name, f.order, where);
    case FactorKind::time: return Values(record_.time.begin(), record_.time.end());
    case FactorKind::elapsed: {
      Values v(n);
      const double t0 = record_.time[window_.first];
      for (std::size_t i = 0; i < n; ++i) v[i] = record_.time[i] - t0;
      return v;
    }
    case FactorKind::window_start: return Values(n, record_.time[window_.first]);
    case FactorKind::initial_value: {
      auto value = initial_value(f, where);
      if (auto* d = std::get_if<Diagnostic>(&value)) return *d;
      return Values(n, std::get<double>(value));
    }
    case FactorKind::function: {
      auto argument = evaluate(*f.argument);
      if (auto* d = std::get_if<Diagnostic>(&argument)) return *d;
      Values v = std::get<Values>(std::move(argument));
      apply_function(f.name, v);
      return v;
    }
    case FactorKind::power: {
      auto argument = evaluate(*f.argument);
      if (auto* d = std::get_if<Diagnostic>(&argument)) return *d;
      Values v = std::get<Values>(std::move(argument));
      const double e = f.exponent.value();
      for (double& x : v) x = std::pow(x, e);
      return v;
    }
    case FactorKind::derivative:
    case FactorKind::integral: {
      const std::string key = print(f);
      if (auto it = composite_.find(key); it != composite_.end()) return it->second;
      if (f.kind == FactorKind::integral && segmented_) {
        // Held or linear inputs: interval by interval within their segments (piecewise_inputs.hpp), from t0.
        auto intervals = interval_integrals(*f.argument, 0);
        if (auto* d = std::get_if<Diagnostic>(&intervals)) return *d;
        const Values& q = std::get<Values>(intervals);
        Values v(n, kNaN);
        if (window_.size() > 0) v[window_.first] = 0;
        for (std::size_t i = 0; i < q.size(); ++i) v[window_.first + i + 1] = v[window_.first + i] + q[i];
        return composite_[key] = std::move(v);
      }
      auto argument = evaluate(*f.argument);
      if (auto* d = std::get_if<Diagnostic>(&argument)) return *d;
      const Values& a = std::get<Values>(argument);
      Values v(n, kNaN);
      if (f.kind == FactorKind::derivative) {
        auto estimate = derivative_operator(options_, f.order, key)->apply(a, record_.step);
        if (auto* d = std::get_if<Diagnostic>(&estimate)) return *d;
        v = std::get<Values>(std::move(estimate));
      } else {
        // eq. 2-1.4: from t0 (the window's first sample) to t; Simpson's rule by default (section 3-2).
        const std::span<const double> slice(a.data() + window_.first, window_.size());
        auto integral = integral_operator(options_)->apply(slice, record_.step);
        if (auto* d = std::get_if<Diagnostic>(&integral)) return *d;
        const Values& c = std::get<Values>(integral);
        std::copy(c.begin(), c.end(), v.begin() + static_cast<std::ptrdiff_t>(window_.first));
      }
      return composite_[key] = std::move(v);
    }
    case FactorKind::guard: {
      Values v(n, 1.0);
      for (const auto& c : f.conditions) {
        auto lhs = evaluate(*c.lhs);
        if (auto* d = std::get_if<Diagnostic>(&lhs)) return *d;
        auto rhs = evaluate(*c.rhs);
        if (auto* d = std::get_if<Diagnostic>(&rhs)) return *d;
        apply_condition(c.relation, std::get<Values>(lhs), std::get<Values>(rhs), v);
      }
      return v;
    }
    case FactorKind::parameter:
    case FactorKind::test_function: break;
  }
  // normalize_pass takes every linear parameter out of the operations, the fit holds the nonlinear
  // ones at values before it evaluates (ir/fix_parameters.hpp), and the weak form's test functions
  // are integrated by runtime/solve/weak_design.cpp before evaluation; one here is a bug (exit code 3).
  throw std::logic_error(fmt::format("the factor `{}` reached the evaluator", print(f)));
}

struct Evaluator::Pieces {
  std::array<SampledRecord, kPieceOffsets.size()> records;
  std::vector<Evaluator> evaluators;  // one per record; they hold references into `records`
};

Evaluator& Evaluator::piece(int d) {
  if (!pieces_) {
    if (boundaries_.empty()) boundaries_ = piece_boundaries(record_, model_);
    pieces_ = std::make_shared<Pieces>();
    pieces_->evaluators.reserve(kPieceOffsets.size());
    for (std::size_t k = 0; k < kPieceOffsets.size(); ++k) {
      pieces_->records[k] = piece_record(record_, model_, kPieceOffsets[k]);
      pieces_->evaluators.emplace_back(pieces_->records[k], model_, options_, window_);
      // The segments are the record's: a piece record's inputs are shifted, their steps with them.
      pieces_->evaluators.back().boundaries_ = boundaries_;
    }
  }
  return pieces_->evaluators[static_cast<std::size_t>(d - kPieceOffsets.front())];
}

std::variant<Evaluator::Stencil, Diagnostic> Evaluator::stencil_values(const ir::Sum& s, const std::string* what) {
  std::vector<ir::Term> smooth, held;  // evaluated once; on the piece records
  for (const auto& t : s.terms) {
    if (has_piecewise_integral(model_, t))
      return diag::held_input_integral_unsupported(t.span, print(ir::canonical(std::vector<ir::Term>{t})), piecewise_input_of(model_, t)->name);
    (piecewise_input_of(model_, t) ? held : smooth).push_back(t);
  }
  auto values_of = [&](Evaluator& e, const ir::Sum& part) { return what ? e.evaluate_in_window(part, *what) : e.evaluate(part); };
  Values common(what ? window_.size() : record_.time.size(), 0.0);
  if (!smooth.empty()) {
    auto values = values_of(*this, ir::canonical(std::move(smooth)));
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    common = std::get<Values>(std::move(values));
  }
  const ir::Sum held_part = ir::canonical(std::move(held));
  Stencil v;
  for (std::size_t j = 0; j < kPieceOffsets.size(); ++j) {
    v[j] = common;
    if (held_part.empty()) continue;
    auto values = values_of(piece(kPieceOffsets[j]), held_part);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    const Values& p = std::get<Values>(values);
    for (std::size_t k = 0; k < p.size(); ++k) v[j][k] += p[k];
  }
  return v;
}

std::pair<int, int> Evaluator::interval_nodes(std::size_t k) {
  if (boundaries_.empty()) boundaries_ = piece_boundaries(record_, model_);
  const bool left = k > window_.first && !boundaries_[k];
  const bool right = k + 2 <= window_.last && !boundaries_[k + 1];
  return {left ? -1 : 0, right ? 2 : 1};
}

std::variant<std::vector<double>, Diagnostic> Evaluator::interval_integrals(const ir::Sum& s, int m) {
  const std::size_t intervals = window_.size() > 0 ? window_.size() - 1 : 0;
  const double h = record_.step;
  double factorial = 1;
  for (int j = 2; j <= m + 1; ++j) factorial *= j;
  Values out(intervals, 0.0);
  std::vector<ir::Term> local;  // the rest: integrated on their pieces
  for (const auto& t : s.terms) {
    if (!has_piecewise_integral(model_, t)) {
      local.push_back(t);
      continue;
    }
    // c * F with F = int(g): int (t_{i+1} - s)^m / m! F = h^(m+1)/(m+1)! F(t_i) + int (t_{i+1} - s)^(m+1)/(m+1)! g.
    const bool integral_alone = t.factors.size() == 1 && t.factors[0].second == 1 && t.factors[0].first.kind == FactorKind::integral;
    if (!integral_alone)
      return diag::held_input_integral_unsupported(t.span, print(ir::canonical(std::vector<ir::Term>{t})), piecewise_input_of(model_, t)->name);
    const ir::Factor& integral = t.factors[0].first;
    auto values = factor(integral, t.span);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    auto inner = interval_integrals(*integral.argument, m + 1);
    if (auto* d = std::get_if<Diagnostic>(&inner)) return *d;
    const Values& F = std::get<Values>(values);
    const Values& g = std::get<Values>(inner);
    const double c = t.coefficient.value(), scale = std::pow(h, m + 1) / factorial;
    for (std::size_t i = 0; i < intervals; ++i) out[i] += c * (scale * F[window_.first + i] + g[i]);
  }
  if (local.empty() || intervals == 0) return out;
  auto stencil = stencil_values(ir::canonical(std::move(local)));
  if (auto* d = std::get_if<Diagnostic>(&stencil)) return *d;
  const Stencil& v = std::get<Stencil>(stencil);  // v[j][k]: sample k as interval k - kPieceOffsets[j] sees it
  const IntervalRules rules(m);
  const double scale = std::pow(h, m + 1);
  for (std::size_t i = 0; i < intervals; ++i) {
    const std::size_t k = window_.first + i;
    const auto& w = rules(interval_nodes(k));
    double total = 0;
    for (std::size_t j = 0; j < kPieceOffsets.size(); ++j)
      if (w[j] != 0.0) total += w[j] * v[j][static_cast<std::size_t>(static_cast<std::ptrdiff_t>(k) + kPieceOffsets[j])];
    out[i] += scale * total;
  }
  return out;
}

std::variant<std::vector<double>, Diagnostic> Evaluator::term(const ir::Term& t) {
  Values v;
  if (auto problem = term_into(t, v)) return *problem;
  return v;
}

std::optional<Diagnostic> Evaluator::term_into(const ir::Term& t, Values& v) {
  const std::size_t n = record_.time.size();
  v.assign(n, t.coefficient.value());
  Values scratch;
  for (const auto& [f, power] : t.factors) {
    auto values = factor_view(f, t.span, scratch);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    const std::span<const double> x = std::get<std::span<const double>>(values);
    // Sample by sample, so a long record's samples split over the cores (parallel_ranges.hpp).
    if (f.kind == FactorKind::guard) {
      // 0 * NaN would be NaN: a guard that is off zeroes the term even where the rest has no value
      // (a derivative at the very edge), as eq. 4-1.9 defines the regions.
      for_parallel_ranges(n, n, [&](std::size_t first, std::size_t last) {
        for (std::size_t i = first; i < last; ++i) v[i] = x[i] == 0.0 ? 0.0 : v[i] * x[i];
      });
      continue;
    }
    const int k_power = power;
    for_parallel_ranges(n, n * static_cast<std::size_t>(std::max(1, k_power)), [&](std::size_t first, std::size_t last) {
      for (std::size_t i = first; i < last; ++i) {
        double p = x[i];
        if (k_power >= 2) {  // x^k = x^(k-1) * x, the block evaluator's ladder: the same bits, and no pow()
          const double base = p;
          for (int k = 2; k <= k_power; ++k) p *= base;
        } else if (k_power != 1) {
          p = std::pow(p, k_power);
        }
        // A term already exactly zero stays zero where a later factor is infinite (x*y^-1 at
        // x = y = 0 evaluates to 0, not NaN); NaN still spreads, so a missing value is never hidden.
        if (v[i] != 0.0 || std::isnan(p)) v[i] *= p;
      }
    });
  }
  return std::nullopt;
}

std::variant<std::vector<double>, Diagnostic> Evaluator::evaluate(const ir::Sum& s) {
  Values total(record_.time.size(), 0.0);
  for (const auto& t : s.terms) {
    auto values = term(t);
    if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
    const Values& v = std::get<Values>(values);
    for (std::size_t i = 0; i < total.size(); ++i) total[i] += v[i];
  }
  return total;
}

std::variant<std::vector<double>, Diagnostic> Evaluator::evaluate_in_window(const ir::Sum& s, const std::string& what) {
  Values total;
  if (auto problem = evaluate_in_window(s, what, total)) return *problem;
  return total;
}

std::optional<Diagnostic> Evaluator::evaluate_in_window(const ir::Sum& s, const std::string& what, std::vector<double>& total) {
  // Term by term, so that a value that is not finite is blamed on the term that made it. Each term
  // in the evaluator's own buffer, kept from sum to sum (a nested sum, inside a function or a der(),
  // gets vectors of its own).
  total.assign(window_.size(), 0.0);
  Values own;
  Values& v = term_buffer_busy_ ? own : term_buffer_;
  const bool was_busy = term_buffer_busy_;
  term_buffer_busy_ = true;
  std::optional<Diagnostic> problem;
  for (const auto& t : s.terms) {
    if ((problem = term_into(t, v))) break;
    // The first sample without a value names the problem; ranges of samples on every core.
    constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
    std::atomic<std::size_t> first_bad{kNone};
    for_parallel_ranges(window_.size(), window_.size(), [&](std::size_t first, std::size_t last) {
      for (std::size_t i = first; i < last; ++i) {
        const double x = v[window_.first + i];
        if (!std::isfinite(x)) {
          std::size_t seen = first_bad.load();
          while (i < seen && !first_bad.compare_exchange_weak(seen, i)) {
          }
          return;
        }
        total[i] += x;
      }
    });
    if (const std::size_t i = first_bad.load(); i != kNone) {
      const ir::Sum single = ir::canonical(std::vector<ir::Term>{t});
      problem = diag::operation_not_finite(t.span, print(single), what, record_.time[window_.first + i], record_.path);
      break;
    }
  }
  term_buffer_busy_ = was_busy;
  return problem;
}

}  // namespace sidc
