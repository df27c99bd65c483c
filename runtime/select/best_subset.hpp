// Exact best-subset search over the candidate operations of one least-squares problem (thesis
// section 2-3: assume the most general equation, let the record say which operations vanish).
//
// Relies on: a TriangularSystem (runtime/solve/least_squares.hpp), i.e. the problem already reduced by
// one orthogonal transformation to G(x) = ||z - R x||^2 + rho^2 (eq. 2-1.7). Nothing here sees the
// rows, so the cost of the search does not depend on the number of samples n.
//
// Method: the dropping-column algorithm with branch and bound (Furnival & Wilson 1974, "leaps and
// bounds"; in the form of Gatu & Kontoghiorghes 2006). Every node of the search tree is a set V of
// columns held as its own triangular factor; a child drops one free unit of V, and its factor
// comes from V's by deleting the unit's columns and restoring triangular form with Givens
// rotations (O(m^2) for m columns, no refactorization). Each subset is a node exactly once.
// The bound: G never decreases when columns are removed, so G(V) is a lower bound on G of every
// subset in V's subtree; a subtree is skipped when that bound already exceeds, at every subset
// size the subtree can reach, the best G known at that size.
//
// Guarantees:
// - Exact up to a stated tolerance: a subtree is skipped only when G(V) > best(s) + tol * G(0) for
//   every reachable size s, with G(0) = ||z||^2 + rho^2 the G of the empty model and tol =
//   BestSubsetOptions::tolerance (default 1e-10, some 10^5 times the rounding of the Givens
//   updates on power-of-two scaled columns). So for every size the reported G is within
//   tol * G(0) of the true minimum, and the reported subset is the true best whenever no other
//   subset of that size comes within tol * G(0) of it (checked against brute force over all
//   subsets in tests/runtime/best_subset_test.cpp, on random and on ill-conditioned designs).
// - Columns are scaled by powers of two (2-norm in [0.5, 1), as in least_squares.cpp) before the
//   search: exact, and it keeps the Givens updates balanced. G is unchanged by scaling.
// - Required columns are in every subset; the columns of a group enter or leave together; the
//   size of a subset is its number of columns (parameters), so with groups some sizes do not
//   occur and are left empty.
// - Never throws on bad numbers: invalid input comes back as a Termination with a message.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "runtime/solve/least_squares.hpp"

namespace sidc {

struct BestSubsetOptions {
  std::vector<int> required;                // columns in every subset (a required group member requires its group)
  std::vector<std::vector<int>> groups;     // columns that enter or leave together; others are alone
  int keep_per_size = 1;                    // report the best few subsets of every size
  int max_size = -1;                        // report sizes up to this many columns (-1: all); also prunes
  double tolerance = 1e-10;                 // relative to G(0), see the header
  bool is_valid(int p, std::string* why) const;
};

struct SubsetFit {
  std::vector<int> columns;  // ascending column indices
  double G = 0;              // eq. 2-1.7 of the least-squares fit on these columns
};

struct BestSubsetSummary {
  enum class Termination { success, invalid_input };
  Termination termination = Termination::invalid_input;
  std::string message;
  // best[s]: up to keep_per_size subsets of s columns, smallest G first (empty when no subset of
  // that size exists or s > max_size).
  std::vector<std::vector<SubsetFit>> best;
  double G_empty = 0;             // G(0) = ||z||^2 + rho^2
  double tolerance_absolute = 0;  // tolerance * G(0)
  std::size_t nodes = 0;          // subsets whose G was computed
  std::size_t subsets_total = 0;  // subsets the constraints allow (2^free units); 0 when > 2^63
};

// Largest number of columns best_subsets accepts (sizes are tracked in a 64-bit mask).
inline constexpr int kBestSubsetMaxColumns = 63;

BestSubsetSummary best_subsets(const TriangularSystem& system, const BestSubsetOptions& options);

// The problem restricted to some of its columns, again in triangular form (Householder QR of the
// chosen columns of R with z; the rest of z goes into rho), with the row totals kept.
TriangularSystem restrict_columns(const TriangularSystem& system, const std::vector<int>& columns);

// Least squares on some columns of a triangle: the coefficients (in the given column order) and G.
// Rank-deficient column sets get the basic solution (dependent coefficients 0) from column-pivoted QR.
struct SubsetSolution {
  std::vector<double> coefficients;
  double G = 0;
  int rank = 0;
};
SubsetSolution solve_subset(const TriangularSystem& system, const std::vector<int>& columns);

// G of a triangle at given coefficients (full length p, zeros for columns not in the model):
// ||z - R x||^2 + rho^2. The test error of a held-out block in cross-validation.
double G_at(const TriangularSystem& system, const std::vector<double>& x);

}  // namespace sidc
