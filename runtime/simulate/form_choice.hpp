// The form of a model's equations chosen from the data, when the model names none (issue 13, item 4).
//
// Each candidate form (the weak form, the derivative form, the integrated form; rewritten by the
// compiler before they reach here) is fitted to the records; each record is cut into kPieces
// stretches of time, and on each the fitted equations are solved from an initial state estimated
// over its start (validate.hpp) and compared with the recorded outputs. The criterion is that
// comparison, the simulation error 100 - fit % of the worst output: it needs no truth, it judges
// every form by the same yardstick (the forms fit different equations, sample rows, integrals from
// t0, test-function integrals, whose own residuals cannot be compared), and it is the one that
// matters to the user. The first candidate (sidc fit puts the weak form first, the most accurate on
// known-truth records, docs/accuracy.md) is kept unless another simulates better on every piece: a
// sign test, passed by chance with probability 2^-5 = 3% for one alternative (about 6% for the
// two, and more since neighbouring pieces are not quite independent); if the first cannot be
// fitted or simulated, the best of the others by total error. A single whole-record comparison is not
// enough: on the benchmark's pendulum with Coulomb friction a derivative-form fit 5.5% off simulated
// the clean record at 99.61% against 99.47% for the weak form's, 0.4% off. Records shorter than
// kPieces * kShortestPiece samples are compared whole (any improvement then counts). A candidate
// that cannot be fitted, solved or simulated to the end scores nothing.
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "ir/explicit_form.hpp"
#include "runtime/simulate/validate.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {

inline constexpr std::size_t kPieces = 5;
inline constexpr std::size_t kShortestPiece = 100;

struct FormCandidate {
  std::string name;        // "derivative", "integrated", "weak"
  const ir::Model* model;  // the rewritten model to fit
};

struct FormScore {
  std::string name;
  std::optional<double> worst_fit_percent;  // nullopt: not fitted, not solvable or not simulated to the end
  std::string note;                         // why not
  std::size_t better_pieces = 0;            // pieces it simulates better than the first candidate
  std::size_t pieces = 0;
};

struct FormChoice {
  std::vector<FormScore> scores;  // in candidate order
  std::size_t chosen = 0;         // index into scores (and the candidates)
  std::string report() const;     // the comparison table for stdout
};

FormChoice choose_form(const std::vector<FormCandidate>& candidates, const ir::Model& normalized,
                       const std::variant<ExplicitForm, Diagnostic>& explicit_form, const std::vector<SampledRecord>& records,
                       const FitOptions& options, std::size_t validate_samples);

}  // namespace sidc
