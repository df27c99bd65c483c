// Forward regression with orthogonal least squares and the error reduction ratio (FROLS: Billings,
// Chen & Korenberg 1989; Billings 2013, ch. 3; SysIdentPy's FROLS), on a problem already reduced
// to a triangle, for candidate sets too large for exact best-subset search (best_subset.hpp).
//
// Relies on: a TriangularSystem (least_squares.hpp). The orthogonalization runs in the p
// coordinates of the triangle: Q^T is orthogonal and the rows' remainder (rho) is orthogonal to
// every column, so projections, and hence every ERR, equal those on the original rows. Cost per
// step O(U p s) for U candidate units and s terms already chosen; nothing depends on n.
//
// Method: start from the required units (entered first, in column order, with their own ERR),
// then repeatedly enter the unit whose columns, orthogonalized against those already chosen
// (modified Gram-Schmidt, twice: Kahan's "twice is enough"), explain the largest share of what is
// left: ERR_u = ||projection of the current residual onto them||^2 / G(0), G(0) = ||w b||^2.
// The cumulative ERR after a step is 1 - G/G(0), with G that of the least-squares fit on the
// terms chosen so far.
//
// Guarantees: each step's chosen columns, ERR, cumulative ERR and G are reported in order (the
// path); a unit whose orthogonalized columns have vanished (norm below 1e-12 of the original: a
// combination of the chosen ones) gets ERR 0 and is chosen only when nothing else is left.
// Stops after max_terms columns, or when every unit is in. Never throws.
#pragma once

#include <string>
#include <vector>

#include "runtime/solve/least_squares.hpp"

namespace sidc {

struct ForwardRegressionOptions {
  std::vector<int> required;
  std::vector<std::vector<int>> groups;
  int max_terms = -1;  // columns; -1: until every unit is in
  bool is_valid(int p, std::string* why) const;
};

struct ForwardStep {
  std::vector<int> entered;  // columns that entered at this step (one unless a group)
  bool required = false;
  double err = 0;             // error reduction ratio of this step
  double cumulative_err = 0;  // sum of the ERR so far = 1 - G / G(0)
  double G = 0;               // of the fit on every column entered so far
};

struct ForwardRegressionSummary {
  enum class Termination { success, invalid_input };
  Termination termination = Termination::invalid_input;
  std::string message;
  double G_empty = 0;
  std::vector<ForwardStep> steps;
};

ForwardRegressionSummary forward_regression(const TriangularSystem& system, const ForwardRegressionOptions& options);

}  // namespace sidc
