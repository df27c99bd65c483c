#include "runtime/simulate/form_choice.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace sidc {
namespace {

// Samples [first, last) of `r`, absolute times kept (inputs written as functions of t still hold).
SampledRecord slice(const SampledRecord& r, std::size_t first, std::size_t last) {
  SampledRecord s;
  s.path = r.path;
  s.step = r.step;
  s.time.assign(r.time.begin() + static_cast<std::ptrdiff_t>(first), r.time.begin() + static_cast<std::ptrdiff_t>(last));
  for (const auto& [name, v] : r.signals) s.signals[name].assign(v.begin() + static_cast<std::ptrdiff_t>(first), v.begin() + static_cast<std::ptrdiff_t>(last));
  s.columns = r.columns;
  if (!r.weights.empty()) s.weights.assign(r.weights.begin() + static_cast<std::ptrdiff_t>(first), r.weights.begin() + static_cast<std::ptrdiff_t>(last));
  s.weights_column = r.weights_column;
  return s;
}

// The simulation error (100 - fit %, the worst output) of each piece; nullopt when one cannot be
// solved or simulated to its end.
std::optional<std::vector<double>> piece_errors(const ir::Model& normalized, const std::variant<ExplicitForm, Diagnostic>& explicit_form,
                                                const FitSummary& summary, const std::vector<SampledRecord>& pieces,
                                                const FitOptions& options, std::size_t validate_samples, std::string& note) {
  std::vector<const SampledRecord*> checked;
  for (const auto& p : pieces) checked.push_back(&p);
  // Every piece is a record given to be compared with: its problem is the candidate's failure.
  const FitValidation v = validate_fit(normalized, explicit_form, summary, checked, 0, options.evaluation, validate_samples, InitialState::estimate,
                                      nullptr, "refined by the output error", {}, false);
  if (v.failed_record) {
    note = v.failed_record->message;
    return std::nullopt;
  }
  if (!v.note.empty() || v.runs.size() != pieces.size()) {
    note = v.note.empty() ? "not simulated" : v.note;
    return std::nullopt;
  }
  std::vector<double> errors;
  for (const auto& run : v.runs) {
    if (!run.simulation.completed()) {
      note = "a simulation stopped early";
      return std::nullopt;
    }
    double worst = 100;
    for (const auto& o : run.outputs) worst = std::min(worst, o.fit_percent);
    errors.push_back(100 - worst);
  }
  return errors;
}

}  // namespace

FormChoice choose_form(const std::vector<FormCandidate>& candidates, const ir::Model& normalized,
                       const std::variant<ExplicitForm, Diagnostic>& explicit_form, const std::vector<SampledRecord>& records,
                       const FitOptions& options, std::size_t validate_samples) {
  FormChoice choice;
  // The pieces compared: each record cut into kPieces stretches of time when all are long enough.
  const bool cut = std::all_of(records.begin(), records.end(), [](const SampledRecord& r) { return r.time.size() >= kPieces * kShortestPiece; });
  std::vector<SampledRecord> pieces;
  for (const auto& r : records) {
    const std::size_t n = r.time.size(), k = cut ? kPieces : 1;
    for (std::size_t i = 0; i < k; ++i) pieces.push_back(slice(r, n * i / k, n * (i + 1) / k));
  }
  std::vector<std::vector<double>> errors(candidates.size());
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    FormScore score{candidates[c].name, std::nullopt, {}, 0, pieces.size()};
    auto fitted = fit(*candidates[c].model, records, options);
    if (auto* d = std::get_if<Diagnostic>(&fitted)) {
      score.note = "not fitted: " + d->message;
    } else if (!std::get<FitSummary>(fitted).is_solution_usable()) {
      score.note = "not fitted: rank deficient";
    } else if (auto e = piece_errors(normalized, explicit_form, std::get<FitSummary>(fitted), pieces, options, validate_samples, score.note)) {
      errors[c] = *e;
      score.worst_fit_percent = 100 - *std::max_element(e->begin(), e->end());
      score.note.clear();
    }
    choice.scores.push_back(std::move(score));
  }
  // The first candidate is kept unless another simulates better on every piece (a sign test:
  // by chance alone that happens with probability 2^-pieces, 3% for 5 pieces) and in all;
  // then the best of those.
  double best_total = 0;
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    FormScore& s = choice.scores[c];
    if (!s.worst_fit_percent) continue;
    double total = 0;
    for (double e : errors[c]) total += e;
    if (c > 0 && choice.scores[0].worst_fit_percent)
      for (std::size_t i = 0; i < pieces.size(); ++i) s.better_pieces += errors[c][i] < errors[0][i] ? 1 : 0;
    const bool eligible = c == 0 || !choice.scores[0].worst_fit_percent || s.better_pieces == pieces.size();
    const bool first_usable = !choice.scores[choice.chosen].worst_fit_percent;
    if (eligible && (first_usable || (c > 0 && (choice.chosen == 0 || total < best_total)))) choice.chosen = c, best_total = total;
    if (c == 0) best_total = total;
  }
  return choice;
}

std::string FormChoice::report() const {
  const std::size_t pieces = scores.empty() ? 0 : scores.front().pieces;
  std::string out = fmt::format(
      "form chosen from the data (the model sets none): each form fitted, its equations solved from an estimated initial state\n"
      "{} and compared with it (fit % of the simulated outputs: the worst output{});\n"
      "the first is kept unless another simulates better on every piece (if the first fails, the best of the others)\n",
      pieces > 1 ? fmt::format("on each of {} pieces of the records", pieces) : std::string("over the whole record (too short to cut)"),
      pieces > 1 ? " and piece" : "");
  for (std::size_t i = 0; i < scores.size(); ++i) {
    const auto& s = scores[i];
    out += fmt::format("  {:<11} {:>10}   {}{}{}\n", s.name, s.worst_fit_percent ? fmt::format("{:.2f}%", *s.worst_fit_percent) : "-",
                       i > 0 && s.worst_fit_percent && scores[0].worst_fit_percent ? fmt::format("better on {} of {} piece{}", s.better_pieces, s.pieces, s.pieces == 1 ? "" : "s") : "", s.note,
                       i == chosen ? "   <- chosen" : "");
  }
  return out;
}

}  // namespace sidc
