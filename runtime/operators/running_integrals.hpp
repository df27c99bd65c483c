// Integrals from t0 (eq. 2-1.4) carried from one stretch of a fit window to the next, so that the
// streamed fit of an integrated form holds one stretch of each integral, never a whole record of it.
//
// Relies on: block_evaluator.hpp for the integrands, simpson.hpp for the rules being carried.
// Guarantees:
// - After advance(last), values() holds every integral occurring in the sums given (nested ones
//   included) on window samples [done before, last), with integrals_first set to match, and every
//   initial value y(t0) they hold.
// - The arithmetic is cumulative_simpson's (or cumulative_trapezoid's) over the whole window,
//   operation for operation, carried across stretches by the value at the last even sample, the
//   last value, and the last three integrand values: given the same integrands, the values are
//   identical, bit for bit, to prepare_whole_window_values'. The integrands are the block
//   evaluator's, which equal Evaluator's bit for bit.
// - Nested integrals are carried innermost first: an outer integrand reads the inner integrals'
//   values on the same stretch.
// - What cannot be carried is said by carries() before any work, and start() then prepares the
//   whole window at once: smoothing before integrating (its moving arc reads beyond a stretch),
//   held or linear inputs (integrated segment by segment), an integral inside a derivative, an
//   integral in the row weights, and windows of fewer than 4 samples (Simpson's first interval
//   reads four samples).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"
#include "runtime/operators/block_evaluator.hpp"
#include "runtime/operators/evaluate.hpp"

namespace sidc {

class RunningIntegrals {
 public:
  // Whether the integrals of `sums` (and the model's weights) can be carried on this window.
  static bool carries(const ir::Model& model, const EvaluationOptions& options, FitWindow window,
                      const std::vector<const ir::Sum*>& sums);

  // The window's integrals and initial values (scalars, evaluated at once): carried when carries()
  // says so (the integrals found, none carried yet), else prepared over the whole record at once by
  // prepare_whole_window_values, which every stretch then reads. Errors: the step is not positive,
  // an initial value cannot be had, an integral cannot be prepared (as Evaluator says).
  static std::variant<RunningIntegrals, Diagnostic> start(const SampledRecord& record, const ir::Model& model,
                                                          const EvaluationOptions& options, FitWindow window,
                                                          const std::vector<const ir::Sum*>& sums);

  // The stretch to advance by: `asked` rows (at least 4) when carried, the whole window when not.
  std::size_t stretch_rows(std::size_t asked) const;

  // Carries every integral over window samples [done(), last) (0-based in the window; at least 4
  // samples on the first call), evaluating the integrands in blocks of `block_rows` on up to
  // `threads` threads. A structural problem of an integrand is a Diagnostic; a value that is not
  // finite is carried (the rows that read it report it). Prepared whole: nothing to do.
  std::optional<Diagnostic> advance(std::size_t last, int threads, std::size_t block_rows);
  // From t0 again (each equation of a group reads the same integrals from the start).
  void restart();

  std::size_t done() const { return done_; }
  const WholeWindowValues& values() const { return values_; }

 private:
  struct Carried {
    std::string key;           // the printed integral factor
    const ir::Sum* integrand;  // its argument
    int depth = 1;             // 1 + the deepest integral inside the integrand
    double even = 0;           // the integral at the last even window sample reached
    double last = 0;           // the integral at the last sample reached
    double history[3] = {0, 0, 0};  // integrand at the last three samples, oldest first
    std::vector<double> integrand_values;  // on the current stretch
  };

  RunningIntegrals(const SampledRecord& record, const EvaluationOptions& options, FitWindow window)
      : record_(&record), options_(options), window_(window) {}
  std::optional<Diagnostic> evaluate_integrands(int depth, std::size_t first, std::size_t last, int threads, std::size_t block_rows);
  void carry(Carried& c, std::size_t first, std::size_t last);

  const SampledRecord* record_;
  EvaluationOptions options_;
  FitWindow window_;
  std::vector<Carried> carried_;  // innermost first (by depth)
  WholeWindowValues values_;
  std::size_t done_ = 0;
  bool prepared_whole_ = false;
};

}  // namespace sidc
