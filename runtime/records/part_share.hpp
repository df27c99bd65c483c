// What cooperating processes ("parts": the ranks of `mpirun -np N sidc ...`, issue 17) do together:
// merge small states in part order, and put long vectors together. A record's byte ranges are
// read this way (records.hpp, CsvOptions::share); a streamed fit's rows are shared on top of it
// (runtime/solve/row_share.hpp).
//
// Relies on: nothing. The runtime knows nothing of how the parts talk: distributed/session.cpp
// implements this over MPI. Guarantees (of every implementation):
// - merge() and concatenate() are collective: every part calls them the same number of times, in
//   the same order.
// - merge() begins with an exchange of every part's status. On `combined`, every part holds the same
//   merged state (the tree is fixed, so every run with the same number of parts gives the same bits).
//   On `problem`, nothing is merged: some part said it has a problem (has_problem), and every part
//   learns it. On `stopped`, another part has left the job with an error of its own (printed by that
//   part): `why` says which, and the caller stops with it.
#pragma once

#include <cstddef>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace sidc {

class PartShare {
 public:
  virtual ~PartShare() = default;
  virtual int part() const = 0;   // 0 .. parts() - 1
  virtual int parts() const = 0;  // at least 1

  enum class Outcome { combined, problem, stopped };
  struct Combined {
    Outcome outcome = Outcome::combined;
    std::string why;  // for `stopped`
  };
  // `left` becomes the state of left's parts followed by right's (right's parts come right after
  // left's, so pieces that must join in order, such as a line fit's running differences, can).
  using Merge = std::function<void(std::vector<double>& left, const std::vector<double>& right)>;

  // Every part's `state` merged in part order, by a binary tree of merge(left, right) (the same tree
  // for the same number of parts), and the result given to every part. States may differ in length.
  virtual Combined merge(std::vector<double>& state, const Merge& merge, bool has_problem) = 0;

  // Every part's `mine` one after another, in part order, into `all` on every part: part k's values
  // go to all[offset_k, offset_k + lengths[k]), offset_k the sum of the lengths before. Lengths as
  // every part knows them (from a merge just before; no status exchange here). Part k's `mine` has
  // lengths[k] values; `all` has their sum.
  virtual void concatenate(std::span<const double> mine, std::span<double> all, std::span<const std::size_t> lengths) = 0;
};

}  // namespace sidc
