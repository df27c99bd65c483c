#include "runtime/simulate/validate.hpp"

#include <cmath>
#include <limits>
#include <fmt/format.h>

#include "runtime/solve/fitted_values.hpp"

namespace sidc {

std::variant<ValidationSummary, Diagnostic> validate(const ir::Model& normalized, const ExplicitForm& form, const std::vector<double>& parameters,
                                                     const SampledRecord& record, const ValidationOptions& options) {
  SimulateOptions o;
  o.method = options.method;
  o.substeps = options.substeps;
  o.absolute_tolerance = o.relative_tolerance = options.tolerance;
  o.parameters = parameters;
  // The first sample where every state derivative has its centred moving-arc estimate, as good
  // as the fit's own: an off-centre estimate at the very first sample can be far off on a rounded
  // record (Appendix A: y'(0) = -2.7 at Delta = 0.020 where the truth is 0).
  std::size_t start = 0;
  auto chosen = state_operators_for_record(form, record, options.evaluation);
  if (auto* d = std::get_if<Diagnostic>(&chosen)) return *d;
  for (const auto& out : form.outputs)
    for (int m = 1; m < out.order; ++m) {
      DerivativeOptions centred = derivative_options_for(std::get<EvaluationOptions>(chosen), out.name, m);
      centred.edges = DerivativeOptions::Edges::drop;
      start = std::max(start, static_cast<std::size_t>(std::max(0, samples_lost_each_side(m, centred))));
    }
  if (start + 1 >= record.time.size()) start = 0;
  const auto from = static_cast<std::ptrdiff_t>(start);
  const auto to = static_cast<std::ptrdiff_t>(options.max_samples > 0 ? std::min(record.time.size(), start + options.max_samples) : record.time.size());
  o.time.assign(record.time.begin() + from, record.time.begin() + to);
  o.t0_for_tau = record.time.front();
  // `y(0)`, `y(t0)`, `y(2.5)`: a recorded output's value, as the fit read it (eq. 4-2.4). Derivatives
  // at a point would need the moving arc there; none of the thesis' models uses one.
  o.initial_value = [&record](const ir::Factor& f) -> std::optional<double> {
    auto it = record.signals.find(f.name);
    if (f.order != 0 || it == record.signals.end() || record.time.size() < 2) return std::nullopt;
    const double at = f.at ? f.at->value() : record.time.front();
    const double k = (at - record.time.front()) / record.step;
    const auto i = static_cast<std::size_t>(std::llround(k));
    if (k < -1e-9 || std::abs(k - std::round(k)) > 1e-6 || i >= it->second.size()) return std::nullopt;
    return it->second[i];
  };
  for (const auto& s : normalized.signals)
    if (s.kind == ir::Signal::Kind::input && !s.definition)
      if (auto it = record.signals.find(s.name); it != record.signals.end()) o.inputs[s.name].assign(it->second.begin() + from, it->second.begin() + to);
  auto initial = initial_state_from_record(form, record, options.evaluation, start);
  if (auto* d = std::get_if<Diagnostic>(&initial)) return *d;
  o.initial = std::get<std::map<std::string, std::vector<double>>>(std::move(initial));

  ValidationSummary v;
  v.record = record.path;
  v.truncated = static_cast<std::size_t>(to) < record.time.size();
  for (const auto& out : form.outputs)
    for (int m = 0; m < out.order; ++m)
      v.initial_state.emplace_back(out.name + std::string(static_cast<std::size_t>(m), '\''), o.initial[out.name][static_cast<std::size_t>(m)]);
  auto run = simulate(normalized, form, o);
  if (auto* d = std::get_if<Diagnostic>(&run)) return *d;
  v.simulation = std::get<SimulationSummary>(std::move(run));

  for (std::size_t j = 0; j < form.outputs.size(); ++j) {
    const auto& recorded = record.signals.at(form.outputs[j].name);
    const std::vector<double> y(recorded.begin() + from, recorded.begin() + to);
    const std::vector<double>& yhat = v.simulation.outputs[j];
    OutputValidation r;
    r.output = form.outputs[j].name;
    std::vector<double> e(y.size());
    double max_observed = 0, mean = 0, sum_e2 = 0, sum_d2 = 0;
    for (std::size_t i = 0; i < y.size(); ++i) {
      e[i] = y[i] - yhat[i];  // eq. 4-1.4: observed - approximated
      if (!std::isfinite(e[i])) continue;
      ++r.samples;
      mean += y[i];
    }
    if (r.samples) mean /= static_cast<double>(r.samples);
    for (std::size_t i = 0; i < y.size(); ++i) {
      if (!std::isfinite(e[i])) continue;
      max_observed = std::max(max_observed, std::abs(y[i]));
      if (std::abs(e[i]) > r.max_abs_error) r.max_abs_error = std::abs(e[i]), r.time_of_max = o.time[i];
      sum_e2 += e[i] * e[i];
      sum_d2 += (y[i] - mean) * (y[i] - mean);
    }
    r.percent_error = max_observed > 0 ? 100 * r.max_abs_error / max_observed : NAN;  // eq. 4-1.5
    r.fit_percent = sum_d2 > 0 ? 100 * (1 - std::sqrt(sum_e2 / sum_d2)) : NAN;
    r.rms_error = r.samples ? std::sqrt(sum_e2 / static_cast<double>(r.samples)) : NAN;
    v.outputs.push_back(r);
    v.recorded.push_back(y);
    v.simulated.push_back(yhat);
    v.error.push_back(std::move(e));
  }
  if (v.simulation.completed()) {
    // The sentence follows from the numbers: "follow it" only when every output's fit % reaches
    // kFollowsFitPercent; otherwise it names each output that falls short, where it departs most
    // and by how much.
    std::string parts, short_of;
    for (const auto& r : v.outputs) {
      const std::string numbers = fmt::format("max |E[{}]| = {:.4g} at t = {:.4g} ({:.3g}% of max |{}|, eq. 4-1.5)", r.output, r.max_abs_error,
                                              r.time_of_max, r.percent_error, r.output);
      parts += (parts.empty() ? "" : "; ") + numbers;
      if (!(r.fit_percent >= kFollowsFitPercent))
        short_of += fmt::format("{}fit {:.3g}% for {} (below {:g}%), {}", short_of.empty() ? "" : "; ", r.fit_percent, r.output, kFollowsFitPercent, numbers);
    }
    v.statement = short_of.empty() ? "The fitted equations, solved from the record, follow it: " + parts + "."
                                   : "The fitted equations, solved from the record, do not follow it: " + short_of + ".";
  } else {
    v.statement = fmt::format("The fitted equations could not be solved over the whole record: {}. The model does not reproduce the record; "
                              "the numbers below cover the samples before t = {:.6g}.",
                              v.simulation.message, v.simulation.stopped_at.value_or(record.time.front()));
  }
  return v;
}

std::string ValidationSummary::report(const std::string& method) const {
  std::string initial;
  for (const auto& [name, value] : initial_state) initial += fmt::format("{}{} = {:.6g}", initial.empty() ? "" : ", ", name, value);
  std::string out = fmt::format("validation (thesis section 2-4): the fitted equations solved by {} against `{}`,\n", method, record);
  out += fmt::format("  from t = {:.6g} with {} (taken from the record; derivatives by the moving arc)\n",
                     simulation.time.empty() ? 0.0 : simulation.time.front(), initial);
  out += fmt::format("  {:<10} {:>8} {:>12} {:>10} {:>16} {:>10} {:>12}\n", "output", "samples", "max |E|", "at t", "%E (eq. 4-1.5)", "fit %", "RMS E");
  for (const auto& r : outputs)
    out += fmt::format("  {:<10} {:>8} {:>12.4g} {:>10.4g} {:>16.3g} {:>10.4g} {:>12.4g}\n", r.output, r.samples, r.max_abs_error, r.time_of_max,
                       r.percent_error, r.fit_percent, r.rms_error);
  out += "  " + statement + "\n";
  return out;
}

FitValidation validate_fit(const ir::Model& normalized, const std::variant<ExplicitForm, Diagnostic>& form, const FitSummary& summary,
                           const std::vector<const SampledRecord*>& records, std::size_t fitted_records, const EvaluationOptions& evaluation,
                           std::size_t max_samples) {
  FitValidation v;
  v.max_samples = max_samples;
  if (!summary.is_solution_usable()) {
    v.note = "skipped: the fit is rank deficient, so its parameters are not worth simulating";
    return v;
  }
  if (auto* d = std::get_if<Diagnostic>(&form)) {
    v.note = "skipped: " + d->message;
    return v;
  }
  const std::vector<double> parameters = fitted_parameter_values(normalized, summary, 0.0);
  ValidationOptions o;
  o.evaluation = evaluation;
  o.max_samples = max_samples;
  for (std::size_t r = 0; r < records.size(); ++r) {
    auto run = validate(normalized, std::get<ExplicitForm>(form), parameters, *records[r], o);
    if (auto* d = std::get_if<Diagnostic>(&run)) {
      if (r >= fitted_records) {  // a --validate record the user named: its problem is an error
        v.failed_record = *d;
        v.failed_path = records[r]->path;
        return v;
      }
      v.note = fmt::format("skipped for `{}`: {}", records[r]->path, d->message);
      continue;
    }
    v.runs.push_back(std::get<ValidationSummary>(std::move(run)));
  }
  return v;
}

std::optional<double> simulation_rms_error(const ir::Model& normalized, const ExplicitForm& form, const std::vector<ParameterIndex>& subset,
                                           const std::vector<double>& values, const std::vector<SampledRecord>& records,
                                           const EvaluationOptions& evaluation, std::size_t max_samples) {
  std::vector<double> parameters(normalized.parameters.size(), 0.0);
  for (std::size_t i = 0; i < subset.size(); ++i)
    // The derivative form's parameters come first in the fitted model's order (integrate_pass.cpp).
    if (!subset[i].record && subset[i].parameter < parameters.size()) parameters[subset[i].parameter] = values[i];
  ValidationOptions v;
  v.evaluation = evaluation;
  v.max_samples = max_samples;
  double squares = 0;
  std::size_t count = 0;
  for (const auto& record : records) {
    auto run = validate(normalized, form, parameters, record, v);
    if (!std::holds_alternative<ValidationSummary>(run)) return std::nullopt;
    const ValidationSummary& s = std::get<ValidationSummary>(run);
    if (!s.simulation.completed()) return std::numeric_limits<double>::infinity();
    for (const auto& out : s.outputs) squares += out.rms_error * out.rms_error * static_cast<double>(out.samples), count += out.samples;
  }
  return count ? std::sqrt(squares / static_cast<double>(count)) : std::optional<double>();
}

}  // namespace sidc
