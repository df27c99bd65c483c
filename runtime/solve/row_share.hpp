// A streamed fit's rows shared among cooperating processes (issue 17): each part folds a contiguous
// share of the rows into its own triangular factor, and the factors are merged (TSQR: Demmel,
// Grigori, Hoemmen, Langou 2008), so that every part goes on with the factor of all the rows.
//
// Relies on: triangular_accumulator.hpp (the factor and its exact state as doubles). The runtime
// knows nothing of how the parts talk: distributed/mpi_row_share.hpp implements this over MPI.
// Guarantees (of every implementation):
// - combine() and sum() are collective: every part calls them the same number of times, in the same
//   order, with vectors of the same length (runtime/solve/fit.cpp calls combine once per streamed
//   group, weak_design.cpp sum once per operation and order of the test function).
// - On `combined`, every part holds the same factor (of all parts' rows, up to rounding: the merge
//   order is fixed, so every run with the same number of parts gives the same bits) and the same
//   element-wise sums of `counts`.
// - On `problem`, no factor is merged: some part met a problem in its rows (a value that is not
//   finite, a guard that cannot be evaluated); the caller then finds the one a single process names
//   by evaluating every row itself.
// - On `stopped`, another part has left the job with an error of its own (printed by that part):
//   `why` says which, and the caller stops with it.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "runtime/solve/triangular_accumulator.hpp"

namespace sidc {

class RowShare {
 public:
  virtual ~RowShare() = default;
  virtual int part() const = 0;   // 0 .. parts() - 1
  virtual int parts() const = 0;  // at least 1

  enum class Outcome { combined, problem, stopped };
  struct Combined {
    Outcome outcome = Outcome::combined;
    std::string why;  // for `stopped`
  };
  virtual Combined combine(TriangularAccumulator& accumulator, std::vector<double>& counts, bool has_problem) = 0;
  // Element-wise sums of `values` over the parts, on every part (weak_design.cpp: each subdomain's
  // integral computed by one part, zeros from the others, so the sums are exact). Collective, and
  // `has_problem` and the outcomes as for combine.
  virtual Combined sum(std::span<double> values, bool has_problem) = 0;

  // Rows [first, last) of `total` that part `k` of `parts` folds: contiguous, in order, as even as
  // whole blocks of `block_rows` allow.
  static std::pair<std::size_t, std::size_t> share_of(std::size_t total, std::size_t block_rows, int k, int parts) {
    const std::size_t blocks = (total + block_rows - 1) / block_rows;
    const auto bound = [&](std::size_t j) { return std::min(total, blocks * j / static_cast<std::size_t>(parts) * block_rows); };
    return {bound(static_cast<std::size_t>(k)), bound(static_cast<std::size_t>(k) + 1)};
  }
};

}  // namespace sidc
