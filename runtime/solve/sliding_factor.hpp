// Least squares over rows that come and go (thesis chapter V: parameters "determined in a local
// neighbourhood"): the triangular factor R of the rows in hand, z = Q^T b and the residual norm
// rho kept as rows enter and leave, so that sliding a window along a record costs O(p^2) a row
// whatever the window's length (runtime/solve/local_fit.hpp).
//
// Relies on: the standard library; plain loops the compiler vectorises. The arithmetic is LINPACK's (Dongarra et al. 1979,
// ch. 10): a row enters by Givens rotations (dchud); a row leaves by the Saunders downdate (dchdd):
// a = R^-T x, alpha^2 = 1 - |a|^2, rotations that carry alpha into R's diagonal. Exponential
// forgetting multiplies the whole factor by sqrt(lambda) (eq. 2-1.6's weights lambda^(age/2)).
//
// Guarantees:
// - After any adds, removes and forgets, R^T R = A^T A and R^T z = A^T b of the rows in hand, up to
//   rounding, and G = rho^2 (eq. 2-1.7) when no downdate lost rho (see remove()).
// - remove() refuses, leaving the factor untouched, when the downdate would lose accuracy: alpha^2
//   = 1 - x^T (A^T A)^-1 x (one minus the leaving row's leverage) below kMinAlphaSquared, or not a
//   number (R singular). The relative error a downdate adds grows like 1/alpha^2, so the caller
//   then factors the remaining rows from scratch (local_fit.cpp counts and reports each).
// - solve() never divides by a zero pivot: a column whose |R_jj| is at most the rank tolerance
//   times its norm (the sine of its angle to the columns before it) makes the solution rank
//   deficient, and then no estimate is given.
#pragma once

#include <cstddef>
#include <vector>

namespace sidc {

struct SlidingSolution {
  int rank = 0;                      // columns independent to the tolerance; == p: estimates given
  std::vector<double> estimates;     // p values when rank == p, else empty
  std::vector<double> standard_errors;
  double G = 0;                      // rho^2: the weighted residual sum of squares (eq. 2-1.7)
};

class SlidingFactor {
 public:
  explicit SlidingFactor(int p);

  void clear();
  // The row x (p values) with known side y, both already multiplied by the row's weight.
  void add(const double* x, double y);
  // Removes a row added before; false (and nothing changed) when the downdate would lose accuracy.
  bool remove(const double* x, double y);
  // Every row's weight multiplied by sqrt(lambda): exponential forgetting.
  void scale(double factor);

  // The least-squares solution of the rows in hand; `rows` (with non-zero weight) for the
  // residual variance G / (rows - p); `tolerance` as LeastSquaresOptions::rank_tolerance (0 =
  // automatic: DBL_EPSILON * max(rows, p)).
  SlidingSolution solve(double rows, double tolerance) const;

  int columns() const { return p_; }
  bool residual_lost() const { return rho_lost_; }  // a downdate found |zeta| > rho: G is not known

  static constexpr double kMinAlphaSquared = 1e-6;

 private:
  double& r(int i, int j) { return R_[static_cast<std::size_t>(i) * static_cast<std::size_t>(p_) + static_cast<std::size_t>(j)]; }
  const double* row(int i) const { return R_.data() + static_cast<std::size_t>(i) * static_cast<std::size_t>(p_); }
  double r(int i, int j) const { return R_[static_cast<std::size_t>(i) * static_cast<std::size_t>(p_) + static_cast<std::size_t>(j)]; }

  int p_;
  std::vector<double> R_;  // p x p, row-major, upper triangle used
  std::vector<double> z_;
  double rho_ = 0;
  bool rho_lost_ = false;
  std::vector<double> work_, c_, s_;  // remove()'s a, rotations
  mutable std::vector<double> scratch_, inverse_;  // solve()'s column norms, R^-1
};

}  // namespace sidc
