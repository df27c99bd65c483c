// One interface for every operator an evaluation applies to a sampled signal: derivatives and
// smoothing (thesis section 3-1, the moving arc) and integrals from the window start (section
// 3-2, Simpson's rule). The evaluators (evaluate.cpp, block_evaluator.cpp) ask derivative_operator()
// or integral_operator() for the operator a factor needs and call it once per column or block,
// never per sample; they do not know which method is behind it.
//
// Relies on: the options in EvaluationOptions (evaluate.hpp) to choose the method. Guarantees:
// apply() never throws; it returns one value per sample it is given (NaN where the operator has
// none) or a Diagnostic without a location, to which the caller adds the span of the term that
// asked. reach() is large enough for block-by-block evaluation to agree bit for bit with the
// whole record (block_evaluator.hpp; tests/runtime/savitzky_golay_test.cpp checks the moving arc).
//
// Adding an operator (a weak-form derivative, say):
//   1. One new file pair, runtime/operators/<method>.hpp and .cpp, with a class deriving from
//      SignalOperator, as MovingArcOperator (savitzky_golay.hpp) and CumulativeIntegralOperator
//      (simpson.hpp) do; list the .cpp in runtime/CMakeLists.txt.
//   2. Register it: a field in EvaluationOptions that selects it, and a branch on that field in
//      derivative_operator() or integral_operator() (signal_operator.cpp). No evaluator changes.
//      For users to choose it, the field also needs its setting (ir/settings.cpp), its translation
//      (runtime/solve/options_from_settings.cpp) and its flag (cli/record_options.cpp), as
//      `derivative = savgol(7, 3)` and `--derivative` have.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"

namespace sidc {

struct EvaluationOptions;

class SignalOperator {
 public:
  virtual ~SignalOperator() = default;

  // What reports call it: "7-point moving arc of order 3, derivative 2".
  virtual std::string name() const = 0;

  // Samples at each end of what apply() is given that come back without a value (NaN); the fit
  // window keeps clear of them (fit_window()). -1 when the options are invalid (apply() then says why).
  virtual int samples_lost_each_side() const = 0;

  // Samples beyond a block, on each side, that apply() must be given for its values on the block
  // to be exactly those it gives on the whole record; nullopt when each value depends on every
  // sample before it (an integral from t0), so that only the whole record will do.
  virtual std::optional<std::size_t> reach() const = 0;

  // The operator on `samples`, uniformly `step` apart.
  virtual std::variant<std::vector<double>, Diagnostic> apply(std::span<const double> samples, double step) const = 0;
};

// The operator `options` choose for the order-th derivative (order 0: smoothing) of `signal` (a
// signal name or a printed der() factor: under savgol(auto) each has its own arc).
std::unique_ptr<const SignalOperator> derivative_operator(const EvaluationOptions& options, int order, const std::string& signal);

// The operator `options` choose for the cumulative integral from the first sample it is given.
std::unique_ptr<const SignalOperator> integral_operator(const EvaluationOptions& options);

}  // namespace sidc
