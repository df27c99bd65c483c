// Evaluation of compiled operations on one block of a record's samples at a time, so that a fit
// of 10^7 rows never holds a whole-record vector per operation (runtime/solve/fit.cpp's streamed path).
//
// Relies on: evaluate.hpp (SampledRecord, FitWindow, Evaluator for the values that are not local
// in time), signal_operator.hpp (derivative_operator() and its reach()). Guarantees:
// - Local operations (signals, their derivatives, der() of sums, time, tau, t0, products, integer
//   powers, functions, guards) are computed on the block plus a margin of samples on each side:
//   a derivative reads its operator's reach() beyond the block (for the k-th moving-arc derivative
//   k * (window - 1) / 2 samples, eqs. 3-1.2 to 3-1.8, and one extra window so that `shorten`
//   edges, which move the stencil off centre near the end of whatever it is given, only touch the
//   margin; an operator without a reach reads the whole record). Values are therefore
//   identical, bit for bit, to Evaluator's on the whole record (integer powers y^k are the same
//   repeated products in both, y^3 = y^2 * y).
// - Values that depend on the whole window (integrals from t0, eqs. 2-1.4 and 2-2.5; initial
//   values y(t0)) are given: evaluated once by an Evaluator over the whole record before the blocks
//   (prepare_whole_window_values) and sliced, identical to the dense path at the cost of 8 bytes per
//   sample for each distinct integral; or carried stretch by stretch (running_integrals.hpp), in
//   memory that does not grow with the record.
// - A value that is not finite is reported with the index of the term that made it and the sample,
//   so that the caller can name the same term and time the dense path names.
#pragma once

#include <cstddef>
#include <map>
#include <span>
#include <string>
#include <tuple>
#include <variant>
#include <vector>

#include "ir/ir.hpp"
#include "diagnostics/diagnostic.hpp"
#include "runtime/operators/evaluate.hpp"

namespace sidc {

// The first value of a sum over a block that is NaN or infinite.
struct NonFiniteValue {
  std::size_t term = 0;    // index into Sum::terms
  std::size_t sample = 0;  // record sample index
};

// Whole-window values shared by the blocks (read-only once prepared, so several threads can share).
// The integrals cover record samples [integrals_first, integrals_first + length): the whole record
// when prepared at once (NaN outside the window), one stretch of the window when carried
// (running_integrals.hpp); a block outside what they cover is a bug (std::logic_error).
struct WholeWindowValues {
  std::map<std::string, std::vector<double>> integrals;  // by printed factor
  std::size_t integrals_first = 0;                        // the record sample of each vector's [0]
  std::map<std::string, double> initial_values;           // by printed factor
};

// Evaluates every integral and initial value occurring in `sums` once over the whole record.
std::variant<WholeWindowValues, Diagnostic> prepare_whole_window_values(const SampledRecord& record, const ir::Model& model,
                                                                        const EvaluationOptions& options, FitWindow window,
                                                                        const std::vector<const ir::Sum*>& sums);

class BlockEvaluator {
 public:
  BlockEvaluator(const SampledRecord& record, const EvaluationOptions& options, FitWindow window,
                 const WholeWindowValues& whole);

  // Selects samples [first, last) of the record (inside the record) and forgets the last block's values.
  void start_block(std::size_t first, std::size_t last);

  // The sum over the block into `out` (last - first values). A structural problem (a signal not in
  // the record, invalid derivative options) is a Diagnostic; a value that is not finite is reported
  // through `bad` (the first by term, then by sample) and still written.
  std::variant<std::monostate, Diagnostic> evaluate(const ir::Sum& s, std::span<double> out,
                                                    std::optional<NonFiniteValue>* bad = nullptr);

 private:
  using Values = std::vector<double>;
  struct Range {
    std::size_t first = 0, last = 0;  // record samples [first, last)
    std::size_t size() const { return last - first; }
    auto key() const { return std::pair{first, last}; }
  };
  std::variant<Values, Diagnostic> sum(const ir::Sum& s, Range r);
  std::variant<Values, Diagnostic> term(const ir::Term& t, Range r);
  std::variant<const Values*, Diagnostic> factor(const ir::Factor& f, const Span& where, Range r);
  std::variant<const Values*, Diagnostic> power_of(const ir::Factor& f, int power, const Span& where, Range r);
  std::variant<Values, Diagnostic> compute_factor(const ir::Factor& f, const Span& where, Range r);
  const std::string& name_of(const ir::Factor& f);

  const SampledRecord& record_;
  EvaluationOptions options_;
  FitWindow window_;
  const WholeWindowValues& whole_;
  Range block_;
  std::map<const ir::Factor*, std::string> names_;  // printed factors, the cache keys
  // (printed factor, power, range) -> values on the range; cleared with each block.
  std::map<std::tuple<std::string, int, std::size_t, std::size_t>, Values> cache_;
};

}  // namespace sidc
