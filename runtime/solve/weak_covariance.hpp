// The weak form's rows weighted by the covariance that the record's noise gives them: generalised
// least squares, iterated (Bortz, Messenger and Dukic, "Direct estimation of parameters in ODE
// models using WENDy", Bull. Math. Biol. 2023).
//
// Why: neighbouring subdomains overlap and share samples, and each row's residual carries the
// noise of its samples through every operation that reads a noisy signal (through y^3 as 3 y^2 e),
// so the rows are correlated and unequally noisy. Least squares that treats them as independent
// rows is consistent but wastes information, and its intervals are wrong in either direction
// (on one Duffing record at 1% noise, 40 noise seeds, they held the truth in 71% to 98% of cases
// as the subdomains' width went from 50 to 37 samples; these held it in 92-93% at every width). To first order
// in the noise e_s of each signal s (white, of the level noise_level.hpp estimates), row j's
// residual r_j = A_j x - b_j moves by sum_s sum_l L_js(l) e_s(l), with
//   L_js(l) = sum_k phi_j^(k)(t_l) q_l dG_k/ds(l),   G_k = sum_c x_c g_ck - g_bk,
// g_ck the part of operation c (g_bk of the known side) that phi_j^(k) multiplies and q_l the
// quadrature weight; so Cov(r) = C(x) = sum_s sigma_s^2 L_s L_s^T, banded (rows whose supports
// overlap). The fit solves C^-1/2 A x = C^-1/2 b by the same least squares (QR), recomputes C at
// the new x, and repeats until x settles; the intervals are then those of whitened, independent
// rows. Only the relative noise levels matter: the residual variance is estimated from the fit as
// before (it is about 1 when the noise explains the residuals, and is reported). Then, to second
// order, each operation's mean shift under the noise, E g(s + e) - g(s) = sum_s sigma_s^2 g''/2
// (exact for cubics: E (y + e)^3 = y^3 + 3 sigma^2 y), is taken out of the rows, with the noise
// variances scaled by that residual variance (the fit calibrates the estimator's levels), and the
// rows are fitted again: on long records, where the random error is small, the shift would
// otherwise be the error (k of a Duffing record of 10^6 samples at 1% noise: 1.3e-4 off, 2.7
// standard errors).
//
// Relies on: ir/differentiate.hpp (partial_derivative of each part by each signal), evaluate.hpp
// (the derivatives on each record's window), test_functions.hpp (phi's quadrature weights),
// Eigen's sparse Cholesky. Guarantees: the rows are left as they are, with a note saying why,
// where the covariance cannot be written (a guard or sign() on a noisy signal, a signal's
// derivative estimated from the data still in an operation, an int() or der() of a noisy signal),
// where no signal is noisy, for weighted rows (eq. 2-1.6), where a derivative is not finite on the
// record, when the iteration does not settle and when the noise does not explain the residuals
// (their weighted variance above 4); otherwise the estimates are those of the last iteration, with
// the residuals b - A x of the corrected rows, unweighted. Never an error: at worst the unweighted
// fit, as before, with the note.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/SparseCore>

#include "ir/ir.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/solve/design.hpp"
#include "runtime/solve/least_squares.hpp"
#include "runtime/solve/weak_design.hpp"

namespace sidc {

struct WeakWeighting {
  bool applied = false;
  int iterations = 0;        // weighted solves after the first, unweighted one
  double residual_variance = 0;  // of the whitened rows: about 1 when the noise levels explain the residuals
  std::string note;          // how, or why not: one line for the report and fit.json
};

// Noise levels by signal name, one map per record (the fit's OperatorReport::noise).
using NoiseBySignal = std::map<std::string, double>;

// The rows' covariance C(x) at the estimates `x` (in the design's column order), rows as
// weak_design() lays them out; a string says why none can be written (see above).
std::variant<Eigen::SparseMatrix<double>, std::string> weak_row_covariance(
    const ir::Model& model, std::vector<Evaluator>& evaluators, const DesignBuilder& design, const std::vector<std::size_t>& equations,
    const WeakDesign& weak, const std::vector<NoiseBySignal>& noise, const Eigen::VectorXd& x);

// Re-solves the weak group `equations` (its design `weak`, of `design`'s columns over the records
// of `evaluators`) by iterated generalised least squares from the unweighted solution `unweighted`.
// Returns the summary to keep (`unweighted` when the weighting does not apply) and how it was made.
std::pair<LeastSquaresSummary, WeakWeighting> weight_weak_rows(
    const ir::Model& model, std::vector<Evaluator>& evaluators, const DesignBuilder& design, const std::vector<std::size_t>& equations,
    const WeakDesign& weak, const std::vector<NoiseBySignal>& noise, const LeastSquaresSummary& unweighted,
    const std::vector<std::string>& columns, const LeastSquaresOptions& options);

}  // namespace sidc
