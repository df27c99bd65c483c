// Streaming least squares: fold blocks of weighted rows into a (p+1) x (p+1) triangular factor, so
// that records of any length (10^7 rows and more) are fitted in memory that does not grow with n.
//
// Relies on: Eigen's HouseholderQR (double), and solve_least_squares(TriangularSystem, ...) in
// least_squares.hpp for the pivoting, rank decision, scaling and statistics.
//
// Guarantees:
// - After any sequence of add_rows / merge, the stored factor T = [R z; 0 rho] satisfies
//   [diag(w) A, diag(w) b] = Q T for an orthogonal Q (Householder QR of the stacked [T; new block],
//   backward stable in double), so G(x) = ||z - R x||^2 + rho^2 for every x (eq. 2-1.7).
// - solve() reports the same statistics as solve_least_squares on all the rows (G from rho^2,
//   residual SD, sqrt(G/n), R^2 from streamed totals, AIC, BIC, covariance, condition numbers,
//   dependent columns), agreeing with it to rounding on problems that are not ill-conditioned
//   (tests/runtime/least_squares_test.cpp). What it cannot do without the rows: refine against the
//   original data (refinement works on the triangle), centre columns, keep per-row residuals
//   (summary.residuals stays empty; residuals_of() computes them in a second pass over the blocks).
// - Two accumulators over disjoint rows can be merged (e.g. blocks fitted on different threads):
//   merge() stacks the two factors and re-triangularises; the result equals one accumulator that
//   saw all rows, up to rounding.
// - add_rows never throws or aborts: a block with a wrong shape, a NaN or infinite entry or a
//   negative weight is rejected whole (nothing is folded), add_rows returns false, and solve()
//   then reports invalid_input, so that a fit never silently misses data.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "runtime/solve/least_squares.hpp"

namespace sidc {

class TriangularAccumulator {
 public:
  explicit TriangularAccumulator(int p);

  // Folds the rows of `block` (m x p) with right-hand sides `rhs` (m) and optional weights (m,
  // eq. 2-1.6: each row multiplied by w_i). Memory: O(p^2) plus a work area of at most
  // kRowsPerFold x (p + 1) doubles, whatever m is.
  bool add_rows(const Eigen::MatrixXd& block, const Eigen::VectorXd& rhs, const Eigen::VectorXd* weights,
                std::string* why = nullptr);

  // The fast path for a producer that can write rows in place (runtime/solve/fit.cpp's streamed fit):
  // rows_area(m) is an m x (p + 1) area [A b] to fill, column-major, valid until the next call;
  // fold_rows_area(m, weights) then folds those m rows, after multiplying row i by weights[i]
  // when weights are given (eq. 2-1.6), with the same checks and the same guarantees as add_rows
  // but without copying the rows: the area is the lower part of the QR's own work matrix
  // [T; rows], and the row totals are taken per block (Chan's combination, as merge does).
  Eigen::Block<Eigen::MatrixXd> rows_area(Eigen::Index m);
  bool fold_rows_area(Eigen::Index m, const double* weights, std::string* why = nullptr);

  // Adds the rows another accumulator has seen (same p). Returns false when p differs.
  bool merge(const TriangularAccumulator& other, std::string* why = nullptr);

  // The whole state as doubles, to send to another process (distributed/, TSQR): the factor, the
  // counts and the constant-column marks, and each long-double total as an exact pair of doubles
  // (hi + lo: a double pair holds a long double's 64-bit mantissa). from_doubles reads it back
  // into an accumulator of the same p (false, with `why`, when the size does not match); the
  // first rejection's text stays with the process that met it.
  std::vector<double> to_doubles() const;
  bool from_doubles(const std::vector<double>& state, std::string* why = nullptr);

  LeastSquaresSummary solve(const std::vector<std::string>& column_names, const LeastSquaresOptions& options) const;

  TriangularSystem system() const;  // what solve() hands to solve_least_squares
  int columns() const { return p_; }
  std::size_t rows() const { return rows_; }  // rows with non-zero weight folded so far
  std::size_t rejected_blocks() const { return rejected_blocks_; }

  // Second pass: the unweighted residuals b - A x of one block for the parameters of a summary.
  static Eigen::VectorXd residuals_of(const Eigen::MatrixXd& block, const Eigen::VectorXd& rhs,
                                      const LeastSquaresSummary& summary);

  static constexpr Eigen::Index kRowsPerFold = 4096;

 private:
  void fold(const Eigen::MatrixXd& weighted_rows);  // rows of [diag(w) A, diag(w) b]
  void note_row(const Eigen::MatrixXd& block, const Eigen::VectorXd& rhs, Eigen::Index i, double weight);

  void note_block(const Eigen::Ref<const Eigen::MatrixXd>& rows, const double* weights);

  int p_;
  Eigen::MatrixXd triangle_;
  Eigen::MatrixXd work_;  // rows_area's work matrix: (p + 1 + capacity) x (p + 1)  // (p+1) x (p+1), upper triangular
  std::size_t rows_ = 0;
  std::size_t rejected_blocks_ = 0;
  std::string first_rejection_;
  // Constant-column detection over rows with non-zero weight (for centred R^2).
  std::vector<char> column_constant_;
  std::vector<double> column_value_;
  // Weighted moments of b with weights w^2 (Welford / Chan), for the total sums of squares.
  long double weight_sum_ = 0, mean_ = 0, centred_squares_ = 0, uncentred_squares_ = 0;
};

}  // namespace sidc
