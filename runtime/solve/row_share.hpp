// A streamed fit's rows shared among cooperating processes (issue 17): each part folds a contiguous
// share of the rows into its own triangular factor, and the factors are merged (TSQR: Demmel,
// Grigori, Hoemmen, Langou 2008), so that every part goes on with the factor of all the rows.
//
// Relies on: part_share.hpp (merge(), its outcomes), triangular_accumulator.hpp (the factor and its
// exact state as doubles). distributed/session.cpp implements this over MPI.
// Guarantees (of every implementation), beside PartShare's:
// - merge(), sum() and combine() are collective: every part calls them the same number of times, in
//   the same order (fit.cpp combines once per streamed group, weak_design.cpp sums once per
//   operation and order of the test function, select's streamed_rows.cpp merges once per record).
// - On `combined`, every part holds the same merged state (of all parts' rows, up to rounding: the
//   tree is fixed, so every run with the same number of parts gives the same bits).
// - On `problem`, nothing is merged: some part met a problem in its rows (a value that is not
//   finite, a guard that cannot be evaluated); the caller then finds the one a single process names
//   by evaluating every row itself.
// - On `stopped`, another part has left the job with an error of its own (printed by that part):
//   `why` says which, and the caller stops with it.
#pragma once

#include <functional>
#include <span>
#include <string>
#include <vector>

#include "runtime/records/part_share.hpp"
#include "runtime/solve/triangular_accumulator.hpp"

namespace sidc {

class RowShare : public PartShare {
 public:
  // Element-wise sums of `values` over the parts, on every part (weak_design.cpp: each subdomain's
  // integral computed by one part, zeros from the others, so the sums are exact).
  virtual Combined sum(std::span<double> values, bool has_problem) = 0;

  // The streamed fit's merge (fit.cpp): every part's factor, and `counts` summed.
  Combined combine(TriangularAccumulator& accumulator, std::vector<double>& counts, bool has_problem);

  // Rows [first, last) of `total` that part `k` of `parts` takes: contiguous, in order, as even as
  // whole blocks of `block_rows` allow.
  static std::pair<std::size_t, std::size_t> share_of(std::size_t total, std::size_t block_rows, int k, int parts) {
    const std::size_t blocks = (total + block_rows - 1) / block_rows;
    const auto bound = [&](std::size_t j) { return std::min(total, blocks * j / static_cast<std::size_t>(parts) * block_rows); };
    return {bound(static_cast<std::size_t>(k)), bound(static_cast<std::size_t>(k) + 1)};
  }
};

}  // namespace sidc
