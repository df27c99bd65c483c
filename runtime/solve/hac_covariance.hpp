// Parameter covariance that stays honest when the rows of a fit are not independent: the
// Newey-West (HAC: heteroskedasticity and autocorrelation consistent) sandwich, for issue 15's
// "intervals that hold".
//
// Why: the classical covariance sigma^2 (A^T A)^-1 (least_squares.hpp) assumes independent rows.
// The equation-error fit's rows are neighbouring samples of one record: a moving-arc derivative
// spreads one sample's noise over a window of rows, an integral from t0 carries it to every later
// row, and a model error is slow. Its residuals are then autocorrelated, and the classical
// intervals are several times too narrow (on known-truth records at 1% noise they held the truth
// for 14% of the parameters in the derivative form, 42% integrated once: docs/accuracy.md).
//
// Method (Newey and West 1987; Andrews 1991; prewhitening as Andrews and Monahan 1992): with scores
// s_i = w_i^2 r_i a_i (the rows of the normal equations),
//   Cov = B Omega B,  B = (A^T W^2 A)^-1 (the classical covariance / sigma^2),
//   Omega = D Omega_u D * n / (n - rank),  D = diag(1 / (1 - rho_j)),
// where rho_j is an AR(1) coefficient fitted to score column j (pooled over segments, |rho_j| at
// most 0.97 so that a near-random-walk score does not blow the recolouring up), u the whitened
// scores, and Omega_u their Bartlett-weighted long-run covariance sum_{|l| < S} (1 - |l|/S)
// Gamma_l, with the bandwidth S from Andrews' AR(1) plug-in on u: S = 1.1447 (alpha T)^(1/3). The
// prewhitening is column by column, not a p x p VAR as Andrews and Monahan's: a VAR's p^2
// coefficients, fitted on the few hundred rows of a typical record, recolour by noise. The scores
// are scaled to unit mean square per column first (the result is mapped back). Lags never cross a
// segment (one record's rows of one equation): rows of different records or equations are not
// neighbours.
//
// Relies on: Eigen. Guarantees: no exceptions; a summary that is not usable, a covariance with
// NaN (dependent columns), work above
// HacOptions::max_work, or fewer than max(50, 10 p) rows per segment (a long-run covariance of p
// scores from fewer is noise) leaves `computed` false with `note` saying why.
#pragma once

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "runtime/solve/least_squares.hpp"

namespace sidc {

struct HacOptions {
  double confidence_level = 0.95;
  // Rows x columns^2 x lags beyond which the sandwich is not computed (about a second of work).
  double max_work = 4e9;
};

struct HacEstimate {
  bool computed = false;
  std::string note;                    // why not computed ("" when computed)
  Eigen::MatrixXd covariance;          // p x p, the model's columns (as the classical one)
  std::vector<double> standard_errors;  // per column
  std::vector<double> ci_low, ci_high;  // estimate -/+ t_{(1+level)/2, n-rank} * standard error
  double level = 0.95;                  // of the intervals
  double bandwidth = 0;                 // S: lags |l| < S weighted 1 - |l|/S
  double lag1_autocorrelation = 0;      // of the residuals, segments mean-removed and pooled
  double band = 0;                      // 2.576 / sqrt(n): the 99% band of a white residual
  bool prewhitening_clamped = false;    // an AR(1) coefficient was brought down to 0.97
};

// The long-run covariance sum_l Gamma_l of a series of score rows (n x p), as the sandwich's middle:
// AR(1)-prewhitened column by column, Bartlett kernel, Andrews' bandwidth, lags within segments.
// Shared by the least-squares sandwich below and instrumental variables' (scores z_i w_i^2 e_i).
struct LongRunCovariance {
  bool computed = false;
  std::string note;          // why not computed
  Eigen::MatrixXd omega;     // p x p, in the scores' units
  double bandwidth = 0;
  bool prewhitening_clamped = false;
};
LongRunCovariance long_run_covariance(const Eigen::MatrixXd& scores, const std::vector<std::size_t>& segment_starts,
                                      double max_work = HacOptions{}.max_work);

// The lag-1 autocorrelation of e, each segment's mean removed, pooled over the segments.
double lag1_autocorrelation(const std::vector<double>& e, const std::vector<std::size_t>& segment_starts);

// The sandwich for the solved least-squares problem min sum (w_i (b_i - A_i x))^2. `residuals` are
// the unweighted b_i - A_i x (LeastSquaresSummary::residuals); `weights` may be null (all 1);
// `segment_starts` are the first rows of the runs of neighbouring rows (0 first, increasing).
HacEstimate hac_covariance(const Eigen::MatrixXd& A, const std::vector<double>& residuals, const Eigen::VectorXd* weights,
                           const std::vector<std::size_t>& segment_starts, const LeastSquaresSummary& summary,
                           const HacOptions& options = {});

}  // namespace sidc
