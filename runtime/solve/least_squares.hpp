// Weighted linear least squares (thesis section 2-1, eqs. 2-1.6 to 2-1.8) with the scaling of
// section 3-2, solved by Householder QR with column pivoting, and the statistics that go with it.
//
// Relies on: Eigen 3.4 (ColPivHouseholderQR, JacobiSVD) and Boost.Math (Student t quantile).
// Nothing here parses model text; the design matrix arrives with one named column per operation.
//
// Guarantees:
// - Never aborts and never throws on bad numbers: NaN or infinite entries, negative weights, fewer
//   rows than columns, mismatched sizes or invalid options come back as a Termination with a
//   message. A column that is identically zero is reported as rank deficiency naming the column.
// - The parameters minimise G = sum_i (w_i r_i)^2 (eq. 2-1.7) of the design exactly as given (the
//   columns are never rebuilt): the QR works on a scaled (optionally centred) copy, and iterative
//   refinement measures its residuals against the original rows in extended precision, so the
//   answer is that of the original problem to the accuracy the data allow. Measured on the eleven
//   NIST StRD linear sets, see docs/accuracy.md and tests/nist/.
// - Rank deficiency is decided by a documented tolerance on the pivots of the scaled design; the
//   columns beyond the rank are named together with the columns they depend on.
//
// Conventions (all stated again in full_report()):
// - Weights (eq. 2-1.6): R_i = w_i r_i with r_i = b_i - A_i x, so every row is multiplied by w_i.
//   A weight of zero removes the row: n counts the rows with non-zero weight.
// - Standard error sqrt(G/n) is the thesis' (Table 4-1.2 footnote); residual SD sqrt(G/(n-rank))
//   is the regression one (NIST's "residual standard deviation").
// - Parameter covariance sigma^2 (R^T R)^-1 is formed in the scaled, pivoted coordinates of the QR
//   and mapped back (x = M S P u; see least_squares.cpp); confidence intervals use the Student t
//   quantile for n - rank degrees of freedom.
// - R^2 is centred, SSR / (SSR + G) with SSR = sum w_i^2 (yhat_i - ybar_w)^2, when the design has a
//   constant column and intercept_in_r2 is set; otherwise uncentred, SSR = sum (w_i yhat_i)^2
//   (NIST's convention for its no-intercept sets). Writing it as SSR / (SSR + G) rather than
//   1 - G / TSS keeps its digits when R^2 is small (Wampler5: R^2 = 0.0022).
//   Both are also given apart (centred_r_squared, uncentred_r_squared): the uncentred one measures
//   the fit against predicting 0, the centred one against predicting the mean of b, so a known
//   side dominated by its mean or a slow drift shows R^2 = 1.000000 uncentred and a centred one
//   far below; the centred one is 1 - G / sum w_i^2 (b_i - ybar_w)^2, negative when the fit does
//   worse than the mean.
// - AIC = n log(G/n) + 2k and BIC = n log(G/n) + k log(n), Gaussian errors with the variance
//   profiled out and additive constants dropped; k = rank (the parameters actually estimated).
//   Only differences between models fitted to the same rows mean anything.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace sidc {

// Arithmetic of the QR factorization and of the refinement residuals. Double-precision QR is
// backward stable: it loses about as many digits as one rounding of the data already costs
// (digits_lost_estimate), so it is as good as the data unless the data are exact (the NIST
// Wampler sets). Extended buys the remaining digits for exact or nearly exact data.
enum class Precision {
  automatic,         // extended when the problem is small (n * p^2 <= extended_work_limit), else double
  double_precision,  // QR in double, residuals in long double (fast: the choice for large n)
  extended,          // QR in long double (64-bit mantissa), residuals in quad (113 bits);
                     // about 6 times the time of double (n = 2000, p = 25: 44 ms against 7 ms)
};

struct LeastSquaresOptions {
  // Section 3-2 (eq. 3-2.4): divide each column by a scale factor before the QR. The factor is a
  // power of two, chosen so that the scaled column's 2-norm lies in [0.5, 1); multiplying by a
  // power of two is exact, so scaling adds no rounding at all. The report gives the condition
  // number before and after.
  bool scale_columns = true;

  // For designs with a constant column c (an intercept): replace every other column a_j by
  // a_j - s_j c, with s_j the weighted mean of a_j divided by the constant (so the column is
  // centred), and map the parameters back exactly: x_j = u_j for j != c, x_c = u_c - sum s_j u_j
  // (a linear map M, applied to the covariance as M Cov M^T). Only the QR sees the centred
  // columns; refinement residuals use the original rows. Ignored when no column is constant.
  bool center_columns = false;

  // Iterative refinement of the augmented system [I A; A^T 0][r; x] = [b; 0] (Bjorck 1967),
  // with residuals of both equations accumulated in a wider type than the QR's (see Precision)
  // against the original rows, and corrections solved with the same QR. Converges to the
  // least-squares solution of the original rows when eps * condition < 1. At most this many
  // correction steps (0 = off); stops early when a step moves no parameter by 1/16 of a double ulp.
  int refinement_steps = 2;

  // Pivot |R_kk| <= rank_tolerance * |R_11| of the scaled design counts as zero: column k is
  // (numerically) a combination of the columns before it. 0 = automatic: DBL_EPSILON * max(n, p),
  // the double-precision resolution of the data whatever arithmetic the QR uses.
  double rank_tolerance = 0;

  // Centred R^2 when the design has a constant column; false forces the uncentred one.
  bool intercept_in_r2 = true;

  Precision precision = Precision::automatic;
  // The work n * p^2 up to which Precision::automatic chooses extended (at the limit, e.g.
  // n = 1600, p = 25, extended costs about 35 ms against 6 ms for double); beyond it, double.
  double extended_work_limit = 1e6;

  double confidence_level = 0.95;  // two-sided, for ParameterEstimate::ci_low / ci_high

  bool is_valid(std::string* why) const;
};

// Which parameter of a model a column estimates (runtime/solve/design.hpp lays the columns out):
// its index in the model's parameters and, for an integration constant fitted once per record,
// that record. The solver itself sees names only; the design labels the estimates.
struct ParameterIndex {
  std::size_t parameter = 0;
  std::optional<std::size_t> record;  // none: one value for every record
  bool operator==(const ParameterIndex&) const = default;
};

struct ParameterEstimate {
  std::string name;
  double value = 0;           // 0 for a column dropped as dependent
  double standard_error = 0;  // NaN when not estimable (dependent column, or n == rank)
  double ci_low = 0;          // value -/+ t_{(1+level)/2, n-rank} * standard_error
  double ci_high = 0;
  std::optional<ParameterIndex> index{};  // set when the columns are a model's (DesignBuilder::label)
};

struct LeastSquaresSummary {
  enum class Termination { success, rank_deficient, invalid_input, too_few_rows };
  Termination termination = Termination::invalid_input;
  std::string message;  // why, when not success (e.g. "weight of row 13 is -1 (weights must be ...)")

  std::size_t n = 0;     // rows with non-zero weight
  std::size_t p = 0;     // columns
  std::size_t rank = 0;  // numerical rank of the scaled design
  std::vector<ParameterEstimate> parameters;  // in column order
  Eigen::MatrixXd covariance;                 // p x p, sigma^2 (R^T R)^-1 mapped back; NaN where
                                              // a dependent column is involved; empty when the
                                              // input was rejected (invalid_input, too_few_rows)

  double G = 0;               // eq. 2-1.7: sum of squared weighted residuals
  double standard_error = 0;  // thesis (Table 4-1.2): sqrt(G/n)
  double residual_sd = 0;     // sqrt(G/(n - rank)); NaN when n == rank
  double r_squared = 0;
  bool r_squared_centred = false;  // which of the two below r_squared is
  double centred_r_squared = 0, uncentred_r_squared = 0;
  double aic = 0, bic = 0;

  // 2-norm condition numbers (sigma_max / sigma_min, from the singular values of the p x p
  // triangular factor) of the weighted design before and after scaling/centring. Infinite when a
  // column is exactly dependent.
  double condition_before = 0, condition_after = 0;
  // log10(condition_after): how many of the ~16 significant digits of the data a relative
  // perturbation of one rounding error in the design entries can cost the parameters (first-order
  // bound; large residuals can cost more, exactly representable data usually cost less). This is a
  // property of the problem, not of the arithmetic: refinement and extended precision remove the
  // arithmetic's own loss (measured by refinement_change) but cannot recover what the rounding of
  // the data has already lost. Expected correct digits ~ 16 - digits_lost_estimate.
  double digits_lost_estimate = 0;

  // Names of (nearly) dependent columns when rank < p: one group per column beyond the rank, that
  // column first, then the columns that reproduce it (|coefficient| >= 1e-6 of the largest in
  // R11^-1 R12, scaled coordinates). A column that is identically zero forms a group alone.
  std::vector<std::vector<std::string>> dependent_groups;

  std::vector<double> residuals;  // unweighted b_i - A_i x of the reported x, per row (all rows,
                                  // zero-weight ones too); empty for streamed rows

  // How the answer was computed.
  bool extended_precision_used = false;
  std::string arithmetic;        // e.g. "QR in long double (64 bits), refinement residuals in quad (__float128) ..."
  bool columns_scaled = false;
  bool columns_centred = false;
  int refinement_steps_taken = 0;
  // max over non-zero x_j of |x_j - x0_j| / |x_j|: how far refinement moved the plain QR
  // solution x0; its -log10 is roughly the number of correct digits the worst parameter of x0
  // had. 0 when refinement is off.
  double refinement_change = 0;
  double rank_tolerance_used = 0;

  std::string brief_report() const;  // one line
  std::string full_report() const;   // options, statistics, parameter table, dependencies
  bool is_solution_usable() const;   // termination == success: a rank-deficient fit returns the
                                     // basic solution (dependent parameters 0) for diagnosis only
};

// The statistics of a solved summary (success or rank_deficient) that are not finite numbers, or
// that a double cannot hold, each as reports name it with why: "G(a) = sum of squared residuals
// (above the largest double, shown as inf)", "the standard error of `a1` (NaN)". The statistics are
// computed from G in extended precision, so data of any scale a double holds give finite ones; what
// remains is G itself beyond a double, and what no scaling can give (no degrees of freedom left,
// n == rank). Columns dropped as dependent are left out: rank deficiency is reported on its own.
std::vector<std::string> unrepresentable_statistics(const LeastSquaresSummary& summary);

const char* to_string(LeastSquaresSummary::Termination termination);
const char* to_string(Precision precision);

// Minimises sum_i (w_i (b_i - A_i x))^2 (eqs. 2-1.6 to 2-1.8). `weights` may be null (all 1).
// column_names must have A.cols() entries; they name parameters and dependent groups.
LeastSquaresSummary solve_least_squares(const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
                                        const std::vector<std::string>& column_names,
                                        const Eigen::VectorXd* weights,
                                        const LeastSquaresOptions& options);

// A least-squares problem already reduced to triangular form by an orthogonal transformation of
// its (weighted) rows, as TriangularAccumulator produces it:
//   G(x) = || z - R x ||^2 + residual_sum_of_squares,
// together with the row totals that the statistics need and the triangle cannot give back.
struct TriangularSystem {
  Eigen::MatrixXd R;                   // p x p upper triangular
  Eigen::VectorXd z;                   // p: the first p entries of Q^T (w .* b)
  double residual_sum_of_squares = 0;  // ||(Q^T (w .* b))_{p+1..n}||^2
  std::size_t rows = 0;                // rows with non-zero weight
  int constant_column = -1;            // a column equal to one non-zero constant on all rows
  double total_sum_of_squares_centred = 0;    // sum w_i^2 (b_i - ybar_w)^2
  double total_sum_of_squares_uncentred = 0;  // sum (w_i b_i)^2
};

// Why a TriangularSystem cannot be searched or solved: R not p x p, z not of size p, or a NaN,
// infinite or negative entry where none may be; nullopt when it is sound. The checks every
// selection method (best_subset, sequential_threshold, forward_regression) starts with.
std::optional<std::string> triangle_problem(const TriangularSystem& system);

// Solves a TriangularSystem with the same options, pivoting, rank decision, refinement (against
// R and z) and statistics as solve_least_squares; R^2 is 1 - G / TSS here and residuals are empty.
// center_columns does not apply (the triangle has no constant column to centre on).
LeastSquaresSummary solve_least_squares(const TriangularSystem& system,
                                        const std::vector<std::string>& column_names,
                                        const LeastSquaresOptions& options);

}  // namespace sidc
