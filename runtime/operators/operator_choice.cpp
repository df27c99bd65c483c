// savgol(auto): noise levels and the arc of least estimated mean-square error (see operator_choice.hpp).
#include "runtime/operators/operator_choice.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <map>
#include <set>

#include "diagnostics/data_catalogue.hpp"
#include "ir/print.hpp"
#include "ir/queries.hpp"
#include "ir/traversal.hpp"

namespace sidc {
namespace {

// Odd windows 5..21, then about 15% apart (odd), up to `widest`.
std::vector<int> candidate_windows(int widest) {
  std::vector<int> w;
  for (int k = 5; k <= std::min(21, widest); k += 2) w.push_back(k);
  for (double k = 21 * 1.15; static_cast<int>(k) <= widest; k *= 1.15) {
    const int odd = static_cast<int>(k) | 1;
    if (odd <= widest && odd > w.back()) w.push_back(odd);
  }
  return w;
}

// One way of forming the d-th derivative with one window and polynomial order: its centred
// stencil for unit spacing (a repeated first-derivative arc composed d times, eq. 3-1.8).
std::vector<double> stencil(int window, int polyorder, int order, bool repeated) {
  if (!repeated || order == 1) {
    return std::get<std::vector<double>>(savitzky_golay_weights({window, polyorder, order, -1, 1.0}));
  }
  const auto first = std::get<std::vector<double>>(savitzky_golay_weights({window, polyorder, 1, -1, 1.0}));
  std::vector<double> c = first;
  for (int k = 1; k < order; ++k) c = compose_stencils(c, first);
  return c;
}

double sum_of_squares(const std::vector<double>& c) {
  double s = 0;
  for (double x : c) s += x * x;
  return s;
}

// sum (a_i - b_i)^2 for two centred stencils of possibly different lengths.
double distance_squared(const std::vector<double>& a, const std::vector<double>& b) {
  const std::vector<double>& wide = a.size() >= b.size() ? a : b;
  const std::vector<double>& narrow = a.size() >= b.size() ? b : a;
  const std::size_t offset = (wide.size() - narrow.size()) / 2;
  double s = 0;
  for (std::size_t i = 0; i < wide.size(); ++i) {
    const double n = i >= offset && i - offset < narrow.size() ? narrow[i - offset] : 0.0;
    s += (wide[i] - n) * (wide[i] - n);
  }
  return s;
}

// The stencil applied at each of `positions` (each at least half the stencil from either end).
std::vector<double> apply_at(const std::vector<double>& c, std::span<const double> y, const std::vector<std::size_t>& positions) {
  const std::size_t h = c.size() / 2;
  std::vector<double> out(positions.size());
  for (std::size_t k = 0; k < positions.size(); ++k) {
    const double* start = y.data() + positions[k] - h;
    double s = 0;
    for (std::size_t i = 0; i < c.size(); ++i) s += c[i] * start[i];
    out[k] = s;
  }
  return out;
}

// Samples an arc loses at each end (edges = drop): its reach.
int reach_of(int window, int order, bool repeated) { return (repeated ? order : 1) * (window / 2); }

}  // namespace

double ArcChoice::rms_error() const { return std::hypot(bias, noise); }

std::string ArcChoice::describe() const {
  const bool repeated = order >= 2 && arc.second == DerivativeOptions::Second::repeated;
  return fmt::format("savgol({}, {}){}", arc.window, arc.polyorder, repeated ? " repeated" : "");
}

std::variant<ArcChoice, Diagnostic> choose_arc(std::span<const double> y, double step, int order, const NoiseLevel& noise,
                                               const DerivativeOptions& base, AutoForms forms, const std::string& signal,
                                               const std::string& record_path) {
  if (order < 1) return data_diag::invalid_signal_options("savgol(auto)", "the derivative order must be at least 1");
  const bool try_direct = order == 1 || forms != AutoForms::repeated;
  const bool try_repeated = order >= 2 && forms != AutoForms::direct;
  const auto n = static_cast<long long>(y.size());
  // The smallest arc: window 5 (the reference, polynomial order two higher, must fit in it);
  // d + 3 for a direct arc of order d >= 3.
  const int smallest = try_direct ? std::max(5, (order + 3) | 1) : 5;
  const int smallest_reach = try_direct ? reach_of(smallest, order, false) : reach_of(smallest, order, true);
  if (n < 2LL * smallest_reach + 1)
    return data_diag::too_short_for_any_arc(record_path, signal, order, y.size(), 2 * smallest_reach + 1);
  // The widest window whose reach keeps within kAutoEdgeShare of the record at each end.
  const auto allowed_reach = std::max<long long>(smallest_reach, static_cast<long long>(kAutoEdgeShare * static_cast<double>(n)));
  const auto widest_for = [&](bool repeated) {
    const long long per = repeated ? order : 1;
    return static_cast<int>(std::min<long long>(kAutoMaxWindow, 2 * (allowed_reach / per) + 1));
  };

  struct Candidate {
    int window, polyorder;
    bool repeated;
  };
  std::vector<Candidate> candidates;
  for (const bool repeated : {false, true}) {
    if ((repeated && !try_repeated) || (!repeated && !try_direct)) continue;
    const int lowest = repeated ? 1 : order;
    for (int w : candidate_windows(widest_for(repeated)))
      for (int p = lowest; p <= lowest + 4; p += 2)
        if (p + 2 <= w - 1) candidates.push_back({w, p, repeated});
  }
  // Positions every candidate (and its reference, of the same reach) reaches: the common interior,
  // thinned to at most kAutoPositions.
  long long margin = 0;
  for (const auto& c : candidates) margin = std::max<long long>(margin, reach_of(c.window, order, c.repeated));
  std::vector<std::size_t> positions;
  if (n > 2 * margin) {
    const auto inner = static_cast<std::size_t>(n - 2 * margin);
    const std::size_t stride = std::max<std::size_t>(1, (inner + kAutoPositions - 1) / kAutoPositions);
    for (std::size_t i = static_cast<std::size_t>(margin); i < static_cast<std::size_t>(n - margin); i += stride) positions.push_back(i);
  }

  const double scale = std::pow(step, order);
  const double sigma2 = noise.sigma * noise.sigma;
  ArcChoice best;
  best.signal = signal;
  best.order = order;
  best.noise_free = noise.constant;
  double best_mse = -1;
  if (noise.constant) candidates.clear();  // nothing to weigh: the smallest arc, below
  // The reference must itself fit the samples of its window to the noise: where even the higher
  // polynomial cannot follow the signal (a window wider than the signal's own scale), both arcs
  // flatten it alike and their difference says nothing. So a candidate counts only when the
  // reference's smoothing residual, y - s*y, has a mean square within three standard errors of
  // what the noise alone gives it, sigma^2 (1 - s_centre) (s a projection).
  double largest = 0;  // rounding in the smoothing residual is not misfit
  for (std::size_t i : positions) largest = std::max(largest, std::abs(y[i]));
  const double floor = 1e-24 * largest * largest;
  for (const auto& c : candidates) {
    const std::vector<double> arc = stencil(c.window, c.polyorder, order, c.repeated);
    const std::vector<double> reference = stencil(c.window, c.polyorder + 2, order, c.repeated);
    const double variance = sigma2 * sum_of_squares(arc) / (scale * scale);
    double bias = 0;
    if (!positions.empty()) {
      const auto smooth = std::get<std::vector<double>>(savitzky_golay_weights({c.window, c.polyorder + 2, 0, -1, 1.0}));
      const auto fitted = apply_at(smooth, y, positions);
      double residual = 0;
      for (std::size_t k = 0; k < positions.size(); ++k) residual += (y[positions[k]] - fitted[k]) * (y[positions[k]] - fitted[k]);
      residual /= static_cast<double>(positions.size());
      const double expected = sigma2 * (1 - smooth[smooth.size() / 2]);
      if (residual > expected * (1 + 3 * std::sqrt(2.0 / static_cast<double>(positions.size()))) + floor) continue;
      const auto a = apply_at(arc, y, positions);
      const auto r = apply_at(reference, y, positions);
      double ms = 0;
      for (std::size_t k = 0; k < a.size(); ++k) ms += (a[k] - r[k]) * (a[k] - r[k]);
      ms /= static_cast<double>(a.size());
      bias = std::sqrt(std::max(0.0, ms - sigma2 * distance_squared(arc, reference))) / scale;
    }
    const double mse = variance + bias * bias;
    if (best_mse < 0 || mse < best_mse) {
      best_mse = mse;
      best.arc = base;
      best.arc.window = c.window;
      best.arc.polyorder = c.polyorder;
      best.arc.second = c.repeated ? DerivativeOptions::Second::repeated : DerivativeOptions::Second::direct;
      best.bias = bias;
      best.noise = std::sqrt(variance);
    }
  }
  if (best_mse < 0) {  // no candidate fits the record's edge share: the smallest arc
    best.arc = base;
    best.arc.window = smallest;
    best.arc.polyorder = try_direct ? order : 1;
    best.arc.second = try_direct ? DerivativeOptions::Second::direct : DerivativeOptions::Second::repeated;
    best.noise = noise.sigma * std::sqrt(sum_of_squares(stencil(smallest, best.arc.polyorder, order, !try_direct))) / scale;
  }
  // Order 1 is the same either way; keep the options' own setting so that names stay as before.
  if (order == 1) best.arc.second = base.second;
  return best;
}

namespace {

// (name, order) of every signal derivative in `s`, and the der() factors (printed, order, the
// signals inside).
struct Needs {
  std::set<std::pair<std::string, int>> signals;
  struct Composite {
    std::string key;
    int order;
    std::set<std::string> inside;
  };
  std::vector<Composite> composites;
};

void collect(const ir::Sum& s, Needs& needs) {
  ir::for_each_factor(s, [&](const ir::Factor& f) {
    if ((f.kind == ir::FactorKind::signal || f.kind == ir::FactorKind::initial_value) && f.order > 0)
      needs.signals.emplace(f.name, f.order);
    if (f.kind == ir::FactorKind::derivative) {
      Needs::Composite c{print(f), f.order, {}};
      ir::for_each_factor(*f.argument, [&](const ir::Factor& g) {
        if (g.kind == ir::FactorKind::signal) c.inside.insert(g.name);
      });
      for (const auto& name : c.inside) needs.signals.emplace(name, f.order);
      needs.composites.push_back(std::move(c));
    }
  });
}

AutoForms forms_of(const EvaluationOptions& options) {
  if (!options.second_given) return AutoForms::direct;
  return options.derivative.second == DerivativeOptions::Second::repeated ? AutoForms::repeated : AutoForms::direct;
}

}  // namespace

std::variant<OperatorReport, Diagnostic> choose_operators(const SampledRecord& record, const ir::Model& model,
                                                          const EvaluationOptions& options,
                                                          const std::vector<std::pair<std::string, int>>& extra) {
  OperatorReport report;
  report.record = record.path;
  report.automatic = options.automatic_derivative;
  std::map<std::string, NoiseLevel> levels;
  // A static model's rows are not a time series (Norris' data): differences of neighbouring rows
  // say nothing about noise, and nothing is differentiated.
  if (is_static(model) && extra.empty()) return report;
  for (const auto& [name, samples] : record.signals) {
    const NoiseLevel level = estimate_noise_level(samples);
    levels[name] = level;
    const auto column = record.columns.find(name);
    report.noise.push_back({name, column == record.columns.end() ? name : column->second, level});
    if (level.constant) report.warnings.push_back(data_diag::constant_signal(record.path, name));
    else if (level.exceeds_variation()) report.warnings.push_back(data_diag::noise_exceeds_variation(record.path, name, level.sigma, level.spread));
  }
  if (!options.automatic_derivative) return report;

  Needs needs;
  for (const auto& e : model.equations) {
    collect(e.known, needs);
    for (const auto& p : e.terms) collect(p.operation, needs);
  }
  for (const auto& pair : extra) needs.signals.insert(pair);
  const AutoForms forms = forms_of(options);
  std::map<std::pair<std::string, int>, ArcChoice> chosen;
  for (const auto& [name, order] : needs.signals) {
    const auto found = record.signals.find(name);
    if (found == record.signals.end()) continue;  // the evaluator names the missing signal
    auto choice = choose_arc(found->second, record.step, order, levels[name], options.derivative, forms, name, record.path);
    if (auto* d = std::get_if<Diagnostic>(&choice)) return *d;
    chosen[{name, order}] = std::get<ArcChoice>(choice);
    report.arcs.push_back(std::get<ArcChoice>(choice));
  }
  for (const auto& c : needs.composites) {
    ArcChoice widest;
    widest.signal = c.key;
    widest.order = c.order;
    widest.arc = options.derivative;  // a der() of no signal (der(t^2)): the options' own arc
    for (const auto& name : c.inside)
      if (auto it = chosen.find({name, c.order}); it != chosen.end() && it->second.arc.window >= widest.arc.window) {
        widest = it->second;
        widest.signal = c.key;
      }
    report.arcs.push_back(widest);
  }
  return report;
}

std::variant<EvaluationOptions, Diagnostic> operators_for_record(const EvaluationOptions& options, const SampledRecord& record,
                                                                 const ir::Model& model,
                                                                 const std::vector<std::pair<std::string, int>>& extra) {
  if (!options.automatic_derivative) return options;
  auto report = choose_operators(record, model, options, extra);
  if (auto* d = std::get_if<Diagnostic>(&report)) return *d;
  return with_arcs(options, std::get<OperatorReport>(report));
}

EvaluationOptions with_arcs(const EvaluationOptions& options, const OperatorReport& report) {
  EvaluationOptions out = options;
  if (!options.automatic_derivative) return out;
  out.chosen.clear();
  for (const auto& a : report.arcs) out.chosen[a.signal][a.order] = a.arc;
  return out;
}

}  // namespace sidc
