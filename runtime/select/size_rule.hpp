// Two judgements `sidc select` makes from numbers alone, apart from the search: the relative-G
// elbow that names the subset size on records whose residual is not noise (a noise-free record
// leaves only the operators' own smooth error), and the test that flags a candidate operation
// whose values over the window are nearly a polynomial in t (a drift absorber of the integrated
// form: int(cos(theta)) ~ t when theta stays small): integrated I times, the operation is nearly
// a polynomial of degree <= I + 1 exactly when the operation before integration (the I-th
// difference of the column) is nearly a line a + b t.
//
// Relies on: Eigen only. Used by select.cpp; docs/selection.md gives the measurements behind the
// defaults.
//
// Guarantees:
// - relative_g_elbow: for best-subset G_k by increasing size, with G_p the G of the largest size
//   (every candidate in: what the record's noise and the operators' error leave), the share left
//   after each step, left_k = log(G_k / G_p) / log(G_{k-1} / G_p), and the elbow: the first size
//   whose step leaves at most `share` of the distance (in log G) that remained to G_p. Scale-free
//   (G in any units, any n); NaN where the distance before the step is 0. Never throws.
// - polynomial_energy_share: the share of a column's energy (sum of squares, not centred) that a
//   polynomial of the given degree in t explains, 1 - RSS / sum v^2 (1 for a constant column, NaN
//   for a zero one), on equally spaced samples (the records' time grid), by Householder QR of a
//   Legendre basis. Not centred, because a drift absorber's danger is its mean: cos(theta) =
//   1 - theta^2/2 is 99.99% constant when theta stays within 0.3 rad.
// - operation_line_share: per column of an equation's rows integrated `integrations` times, the
//   polynomial_energy_share (degree 1) of its I-th difference, the operation before integration. Measured
//   there, the test does not depend on the record's length: on the integrated column itself every
//   operation with a nonzero mean (y'^2, a damper's y'*[y' <= 0]) becomes a near-ramp on a long
//   enough record, true operations included.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Dense>

namespace sidc {

// The share of the log-distance to the floor that the elbow step may leave (docs/selection.md:
// 0.1 recovered the true size in most of the measured records; 0.05 and 0.2 in fewer).
inline constexpr double kElbowShare = 0.1;

// A candidate whose values are this close to a polynomial in t over the window (share of centred
// variance explained) is flagged as a drift absorber (docs/selection.md: true operations of the
// measured records stay below 0.99, the absorbers above 0.9999). Of the operation before
// integration, see operation_line_share.
inline constexpr double kDriftAbsorberShare = 0.999;

struct ElbowResult {
  std::vector<double> left;  // per size (as given): share of log(G_{k-1}/G_p) left after the step; NaN for the first
  int index = -1;            // the elbow (index into G), -1 when G has fewer than two sizes
};

ElbowResult relative_g_elbow(const std::vector<double>& G, double share = kElbowShare);

// Per column of `values` (rows: equally spaced samples in time), the polynomial share.
std::vector<double> polynomial_energy_share(const Eigen::Ref<const Eigen::MatrixXd>& values, int degree);
std::vector<double> operation_line_share(const Eigen::Ref<const Eigen::MatrixXd>& values, int integrations);

// operation_line_share over rows that arrive piece by piece, on one thread or several (the
// streamed selection): the sums of the line's normal equations per piece (the Legendre basis of
// degree 1 is well conditioned: a 2 x 2 Gram matrix near diag(n, n/3)), joined in row order; the
// differences that straddle two pieces are formed at the join from the last and first I rows
// each piece keeps. The differences are operation_line_share's, value for value; the shares agree
// with it to rounding (the projection's energy over the total, where it takes 1 - RSS / total).
class LineShareSums {
 public:
  // `rows`: the equation's rows in all (W, before differencing), `p` columns, I = `integrations`.
  LineShareSums(std::size_t rows, Eigen::Index p, int integrations);
  // Rows [first, first + block.rows()) of the equation; the first call names where this piece
  // starts, and each later call continues where the last ended.
  void add(std::size_t first, const Eigen::Ref<const Eigen::MatrixXd>& block);
  // Appends the piece `next`, whose rows start where this one's end.
  void join(const LineShareSums& next);
  std::vector<double> shares() const;
  // The whole state as doubles (to merge pieces made by other processes, row_share.hpp), and back:
  // from_doubles gives false for a state of another shape.
  std::vector<double> to_doubles() const;
  bool from_doubles(const std::vector<double>& state);

 private:
  void accumulate(std::size_t first_level0, const Eigen::Ref<const Eigen::MatrixXd>& rows);  // the I-th differences of `rows`
  void differences_in_work(std::size_t first_level0);
  void add_sums(std::size_t first, const Eigen::Ref<const Eigen::MatrixXd>& differences);

  std::size_t n_;  // differenced rows in all
  int integrations_;
  std::size_t first_ = 0, count_ = 0;  // this piece's rows
  Eigen::MatrixXd head_, tail_;        // its first and last min(I, count) rows
  double gram_[3] = {0, 0, 0};         // sum 1, sum x, sum x^2
  Eigen::MatrixXd cross_;              // 2 x p: sum v, sum x v
  Eigen::VectorXd squares_;            // p: sum v^2
  Eigen::MatrixXd work_;               // accumulate's differences
};

}  // namespace sidc
