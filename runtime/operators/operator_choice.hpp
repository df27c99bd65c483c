// `derivative = savgol(auto)`: the moving arc (window and polynomial order, thesis section 3-1)
// chosen per signal and per derivative order from the record itself, by the estimated mean-square
// error of the derivative. The thesis leaves this choice to the investigator ("the most difficult
// and uncertain" operation, chapter V); here it is made from the data and reported.
//
// The criterion, for the d-th derivative of a signal y with spacing h and noise level sigma
// (noise_level.hpp), over candidate arcs c (centred weights for unit spacing):
//   variance  V(c) = sigma^2 * sum_i c_i^2 / h^(2d)  (white noise through the linear stencil);
//   bias      B(c)^2 = mean_n (c*y - r*y)_n^2 / h^(2d) - sigma^2 * sum_i (c_i - r_i)^2 / h^(2d),
//             floored at 0, where r is the arc of the same window and polynomial order two
//             higher: its bias is of a higher power of the window, so c*y - r*y is the bias of c
//             plus noise whose mean square is known and subtracted (an empirical, Lepski-type
//             bias estimate; no higher derivative of y is estimated);
//   and the arc minimising V + B^2 is used. Its rms error sqrt(V + B^2), bias and noise shares are
//   reported. Candidates: windows 5, 7, ..., 21, then about 15% apart, up to the widest whose
//   half-width (d half-widths for a repeated arc) is at most kAutoEdgeShare of the record (the
//   fit window loses that at each end under `edges = drop`) and at most kAutoMaxWindow; polynomial
//   orders d, d + 2, d + 4 (orders of the other parity give the same centred weights). Ties go to
//   the smaller window, then the lower order; a constant signal gets the smallest arc (window 5,
//   order d; 7 for d = 3) without weighing. A candidate counts only where its reference fits the
//   samples of its window to the noise (operator_choice.cpp says why). Second and higher derivatives: the direct arc of that order
//   (see docs/accuracy.md for the measurement that chose it) unless `second_derivative` is written,
//   in which case only that way is searched.
//
// Relies on: savitzky_golay.hpp (weights), noise_level.hpp, the model (which signals and orders it
// differentiates) and evaluate.hpp's EvaluationOptions. Guarantees: deterministic, the same choice
// for the same signal, order and options whatever the model (so fit, select, validation and
// pictures agree); a record too short for the smallest arc is a Diagnostic naming the signal; a
// constant signal and a signal whose noise exceeds its variation give warnings naming it.
#pragma once

#include <span>
#include <string>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/operators/noise_level.hpp"
#include "runtime/operators/savitzky_golay.hpp"
#include "runtime/records/sampled_record.hpp"

namespace sidc {

inline constexpr double kAutoEdgeShare = 0.05;  // an arc's reach is at most 5% of the record at each end
inline constexpr int kAutoMaxWindow = 201;
inline constexpr std::size_t kAutoPositions = 4000;  // samples the criterion is averaged over, at most

// How savgol(auto) may form a derivative of order >= 2.
enum class AutoForms { direct, repeated, both };

struct ArcChoice {
  std::string signal;  // a signal name, or a printed der() factor
  int order = 1;
  DerivativeOptions arc;      // window, polynomial order and the way to higher orders; edges as set
  double bias = 0;            // estimated rms bias over the record, in signal units per time^order
  double noise = 0;           // estimated rms of the noise's share, same units
  bool noise_free = false;    // a constant signal (noise 0, no variation): the smallest arc
  double rms_error() const;   // sqrt(bias^2 + noise^2), the criterion's value
  // "savgol(17, 3)", "savgol(9, 3) repeated" for a repeated arc of order >= 2.
  std::string describe() const;
};

// The arc for the order-th derivative of `y` (spacing `step`, noise level `noise`), edges and the
// way to higher orders from `base`. Errors: order < 1, or fewer samples than the smallest arc
// (the message names `signal`).
std::variant<ArcChoice, Diagnostic> choose_arc(std::span<const double> y, double step, int order, const NoiseLevel& noise,
                                               const DerivativeOptions& base, AutoForms forms, const std::string& signal,
                                               const std::string& record_path);

struct SignalNoise {
  std::string signal;
  std::string column;  // the record column it came from
  NoiseLevel level;
};

// One record's noise levels and, under savgol(auto), the arcs chosen for it.
struct OperatorReport {
  std::string record;
  bool automatic = false;
  std::vector<SignalNoise> noise;  // every signal of the record, in name order
  std::vector<ArcChoice> arcs;     // every (signal, order) the model differentiates (auto only)
  std::vector<Diagnostic> warnings;
};

// The noise level of every signal of `record` (none for a static model, whose rows are not a time
// series) and, when options.automatic_derivative, the arc of
// every derivative `model` estimates from it (`extra` adds (signal, order) pairs that something
// else needs, e.g. validation's initial state). A der() of a sum uses, at its order, the widest arc
// chosen for the signals inside it (the smoothest; its argument is not a recorded signal).
std::variant<OperatorReport, Diagnostic> choose_operators(const SampledRecord& record, const ir::Model& model,
                                                          const EvaluationOptions& options,
                                                          const std::vector<std::pair<std::string, int>>& extra = {});

// `options` with the arcs of `report` (one record's) filled in (unchanged without savgol(auto)).
EvaluationOptions with_arcs(const EvaluationOptions& options, const OperatorReport& report);

// `options` with the arcs chosen for `record` filled in (unchanged without savgol(auto)).
std::variant<EvaluationOptions, Diagnostic> operators_for_record(const EvaluationOptions& options, const SampledRecord& record,
                                                                 const ir::Model& model,
                                                                 const std::vector<std::pair<std::string, int>>& extra = {});

}  // namespace sidc
