// One record's rows for `sidc select`, streamed: evaluated block by block (block_evaluator.hpp,
// integrals carried stretch by stretch by running_integrals.hpp) on every core and folded into the
// selection's time-block triangles and the drift test's sums, so that nothing of the record's
// length is held (issue 16). select.cpp uses it when the record's design would exceed
// FitOptions::stream_above_entries, as fit streams; below that it builds the rows whole.
//
// Relies on: design.hpp (the same rows, weights and interleaving of equations as the whole
// design), TriangularAccumulator, size_rule.hpp's LineShareSums. Guarantees:
// - On success the record's rows are in `blocks` (row of sample i in time block b when
//   W b / F <= i < W (b + 1) / F, as select.hpp says) and each equation's operation_line_share is
//   in `shares`; the triangles and shares equal the whole design's to rounding.
// - Nothing is folded unless every row is: a value that is not finite, a weight that is not a
//   finite number >= 0, or any other problem leaves `blocks` untouched and returns
//   `use_whole_rows`, so that the caller builds the record's rows whole and reports the problem
//   in its words (the streamed pass does not word diagnostics of its own).
#pragma once

#include <cstddef>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/solve/design.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/solve/triangular_accumulator.hpp"

namespace sidc {

enum class StreamedRows { folded, use_whole_rows };

// Record `r` of `design` (its group `members`) over `window`, into the F = blocks.size() time-block
// triangles; `shares[k]` becomes equation members[k]'s line share per column. A Diagnostic only for
// what the whole rows would meet first as well (an initial value that cannot be had, a step that is
// not positive).
std::variant<StreamedRows, Diagnostic> stream_record_rows(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                          std::size_t r, const EvaluationOptions& evaluation, FitWindow window,
                                                          const DesignBuilder& design, const std::vector<std::size_t>& members,
                                                          const FitOptions& options, std::vector<TriangularAccumulator>& blocks,
                                                          std::vector<std::vector<double>>& shares);

}  // namespace sidc
