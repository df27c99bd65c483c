// Weighted least squares by column-pivoted Householder QR (see least_squares.hpp).
//
// Relies on: Eigen's ColPivHouseholderQR and JacobiSVD instantiated for double and for the
// extended type; Boost.Math's Student t quantile. Guarantees: the statements of the header.
//
// The computation, in the order it happens:
//  1. Check the input; any bad number or size is a Termination with a message, never a throw.
//  2. Choose the column transform x = M S u (S: power-of-two scaling, eq. 3-2.4; M: optional
//     centring on a constant column). The working design is W = diag(w) A M S.
//  3. Factor W P = Q R in the working precision (double, or the extended type) and decide the
//     rank from the pivots. Columns beyond the rank are fixed at zero and named (with the
//     columns they depend on, from R11^-1 R12).
//  4. Refine [r; x] on the augmented system with residuals accumulated in the extended type
//     against the ORIGINAL rows (Bjorck 1967), so the transform and the QR's rounding only
//     affect the speed of convergence, not the answer.
//  5. Statistics from the reported (double) x: residuals, G (eq. 2-1.7), sqrt(G/n) (Table
//     4-1.2), residual SD, R^2, AIC, BIC, covariance sigma^2 M S P R11^-1 R11^-T P^T S M^T.
#include "runtime/solve/least_squares.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Dense>
#include <boost/math/distributions/students_t.hpp>
#include <fmt/format.h>

// Two wider types. Extended: the QR's arithmetic when Precision::extended is chosen, and the
// accumulator of every sum in the statistics: long double where it has at least 64 mantissa bits
// (x86-64 Linux), else Boost's software quad. Quad: the residuals of refinement in extended mode
// (113 bits): GCC/Clang's __float128 where it exists (about 90 ns per multiply-add here), else
// long double if that is already quad (aarch64 Linux), else Boost's cpp_bin_float_quad (about 340
// ns). SIDC_PORTABLE_QUAD forces the Boost types, to check that the code compiles with them.
#if LDBL_MANT_DIG >= 64 && !defined(SIDC_PORTABLE_QUAD)
namespace sidc {
using ExtendedScalar = long double;
constexpr const char* kExtendedName = "long double";
}  // namespace sidc
#else
#include <boost/multiprecision/cpp_bin_float.hpp>
#include <boost/multiprecision/eigen.hpp>
namespace sidc {
using ExtendedScalar = boost::multiprecision::cpp_bin_float_quad;
constexpr const char* kExtendedName = "quad (Boost cpp_bin_float_quad)";
}  // namespace sidc
#endif

#if LDBL_MANT_DIG >= 113 && !defined(SIDC_PORTABLE_QUAD)
namespace sidc {
using QuadScalar = long double;
constexpr const char* kQuadName = "quad (long double)";
}  // namespace sidc
#elif defined(__SIZEOF_FLOAT128__) && !defined(SIDC_PORTABLE_QUAD)
namespace sidc {
__extension__ typedef __float128 QuadScalar;
constexpr const char* kQuadName = "quad (__float128)";
}  // namespace sidc
#else
#include <boost/multiprecision/cpp_bin_float.hpp>
namespace sidc {
using QuadScalar = boost::multiprecision::cpp_bin_float_quad;
constexpr const char* kQuadName = "quad (Boost cpp_bin_float_quad)";
}  // namespace sidc
#endif

namespace sidc {

using Index = Eigen::Index;

namespace {

using Ext = ExtendedScalar;
template <class T>
using Matrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;
template <class T>
using Vector = Eigen::Matrix<T, Eigen::Dynamic, 1>;
using ExtVector = Vector<Ext>;
using ExtMatrix = Matrix<Ext>;

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

// A column k beyond the rank "depends on" column m < rank when |(R11^-1 R12)_mk| reaches this
// share of the largest coefficient; in scaled coordinates all columns have norm ~1, so smaller
// coefficients are rounding, not dependence.
constexpr double kDependenceShare = 1e-6;

// Refinement stops once no parameter moves by more than this fraction of a double ulp: the
// reported parameters are doubles, so further steps cannot change them.
constexpr double kConvergedShareOfUlp = 1.0 / 16;

template <class T>
double to_double(const T& value) {
  return static_cast<double>(value);
}

template <class T>
T magnitude(const T& value) {
  return value < T(0) ? -value : value;  // std::abs has no __float128 overload
}

template <class T>
int mantissa_bits() {
  if constexpr (std::numeric_limits<T>::is_specialized) {
    return std::numeric_limits<T>::digits;
  } else {
    return 113;  // __float128 without <quadmath.h>'s numeric_limits in strict mode
  }
}

template <class T>
using AccVector = std::vector<T>;

// The rows of the problem, never modified. For a TriangularSystem they are R and z (no weights).
struct Rows {
  const Eigen::MatrixXd& A;
  const Eigen::VectorXd& b;
  const Eigen::VectorXd* w;
  double weight(Index i) const { return w ? (*w)(i) : 1.0; }
  Index n() const { return A.rows(); }
  Index p() const { return A.cols(); }
};

// x = M S u. S = diag(scale) (powers of two, exact); M = identity except row c, where
// M(c, j) = -shift_j (j != c): centring column j on the constant column c (see the header).
struct ColumnTransform {
  std::vector<double> scale;
  int centre_column = -1;
  std::vector<Ext> shift;  // shift[c] == 0

  template <class T>
  AccVector<T> to_original(const AccVector<T>& u) const {  // x = M S u
    AccVector<T> x(u.size());
    for (std::size_t j = 0; j < u.size(); ++j) x[j] = T(scale[j]) * u[j];
    if (centre_column >= 0) {
      T correction = 0;
      for (std::size_t j = 0; j < x.size(); ++j) correction += T(shift[j]) * x[j];
      x[static_cast<std::size_t>(centre_column)] -= correction;
    }
    return x;
  }
  template <class T>
  AccVector<T> to_work_transposed(const AccVector<T>& v) const {  // S M^T v
    AccVector<T> t = v;
    if (centre_column >= 0) {
      const T centre = v[static_cast<std::size_t>(centre_column)];
      for (std::size_t j = 0; j < t.size(); ++j) {
        if (static_cast<int>(j) != centre_column) t[j] -= T(shift[j]) * centre;
      }
    }
    for (std::size_t j = 0; j < t.size(); ++j) t[j] *= T(scale[j]);
    return t;
  }
  // The working design entry W(i, j) = w_i (a_ij - shift_j a_ic) s_j, in the extended type.
  Ext work_entry(const Rows& rows, Index i, Index j) const {
    Ext a = Ext(rows.A(i, j));
    if (centre_column >= 0 && j != centre_column) a -= shift[static_cast<std::size_t>(j)] * Ext(rows.A(i, centre_column));
    return Ext(rows.weight(i)) * a * Ext(scale[static_cast<std::size_t>(j)]);
  }
};

// What one factorization in one precision produced, in original coordinates.
struct Attempt {
  std::vector<double> x;
  ExtMatrix covariance_unit;  // (R^T R)^-1 mapped back to x; rows/columns of dropped columns NaN
  std::size_t rank = 0;
  std::vector<bool> dropped;  // column is beyond the rank (fixed at zero)
  std::vector<std::vector<Index>> dependent_groups;
  double condition_before = kNaN, condition_after = kNaN, condition_retained = kNaN;
  int refinement_steps_taken = 0;
  double refinement_change = 0;
};

double condition_of(const Eigen::VectorXd& singular_values) {
  if (singular_values.size() == 0) return kNaN;
  const double largest = singular_values.maxCoeff();
  const double smallest = singular_values.minCoeff();
  if (!(smallest > 0)) return kInf;
  return largest / smallest;
}

template <class Work>
Eigen::VectorXd singular_values_of(const Matrix<Work>& square) {
  Eigen::JacobiSVD<Matrix<Work>> svd(square);
  Eigen::VectorXd values(svd.singularValues().size());
  for (Index i = 0; i < values.size(); ++i) values(i) = to_double(svd.singularValues()(i));
  return values;
}

// Residuals of the augmented system [I W; W^T 0][r; u] = [w.*b; 0], measured with the original
// rows in the accumulation type: f = w.*b - r - diag(w) A x and g = -S M^T A^T diag(w) r.
template <class Acc>
void augmented_residuals(const Rows& rows, const ColumnTransform& transform, const AccVector<Acc>& x,
                         const AccVector<Acc>& r, AccVector<Acc>& f, AccVector<Acc>& g) {
  const Index n = rows.n(), p = rows.p();
  f.assign(static_cast<std::size_t>(n), Acc(0));
  AccVector<Acc> weighted_transpose_r(static_cast<std::size_t>(p), Acc(0));
  for (Index i = 0; i < n; ++i) {
    const auto row = static_cast<std::size_t>(i);
    const Acc w = Acc(rows.weight(i));
    Acc fitted = 0;
    for (Index j = 0; j < p; ++j) fitted += Acc(rows.A(i, j)) * x[static_cast<std::size_t>(j)];
    f[row] = w * Acc(rows.b(i)) - r[row] - w * fitted;
    const Acc wr = w * r[row];
    for (Index j = 0; j < p; ++j) weighted_transpose_r[static_cast<std::size_t>(j)] += Acc(rows.A(i, j)) * wr;
  }
  g = transform.to_work_transposed(weighted_transpose_r);
  for (Acc& entry : g) entry = -entry;
}

// Steps 3 and 4 with the QR in Work and refinement residuals in Acc.
template <class Work, class Acc>
Attempt fit_in(const Rows& rows, const ColumnTransform& transform, double rank_tolerance,
               int refinement_steps) {
  const Index n = rows.n(), p = rows.p();
  const auto p_size = static_cast<std::size_t>(p);
  Matrix<Work> W(n, p);
  for (Index j = 0; j < p; ++j) {
    for (Index i = 0; i < n; ++i) W(i, j) = static_cast<Work>(transform.work_entry(rows, i, j));
  }
  Eigen::ColPivHouseholderQR<Matrix<Work>> qr;
  qr.setThreshold(Work(rank_tolerance));
  qr.compute(W);
  const Matrix<Work> R = qr.matrixQR().topLeftCorner(p, p).template triangularView<Eigen::Upper>();
  const auto& pivots = qr.colsPermutation().indices();  // W P = Q R: column l of W P is W.col(pivots(l))

  Attempt attempt;
  // Rank: the leading pivots that stay above the tolerance relative to |R_11| (column pivoting
  // keeps |R_kk| non-increasing, so the first small pivot ends the independent set).
  using std::abs;
  const Work largest_pivot = abs(R(0, 0));
  Index rank = 0;
  while (rank < p && largest_pivot > Work(0) && abs(R(rank, rank)) > Work(rank_tolerance) * largest_pivot) ++rank;
  attempt.rank = static_cast<std::size_t>(rank);
  attempt.dropped.assign(p_size, false);
  for (Index l = rank; l < p; ++l) attempt.dropped[static_cast<std::size_t>(pivots(l))] = true;

  const auto R11 = R.topLeftCorner(rank, rank).template triangularView<Eigen::Upper>();

  // Each dropped column, with the retained columns that reproduce it: W_k ~ W_1 (R11^-1 R12)_k.
  for (Index l = rank; l < p; ++l) {
    std::vector<Index> group{pivots(l)};
    if (rank > 0) {
      const Vector<Work> coefficients = R11.solve(R.col(l).head(rank));
      double share = 0;
      for (Index m = 0; m < rank; ++m) share = std::max(share, to_double(abs(coefficients(m))));
      if (share > 0 && std::isfinite(share)) {
        for (Index m = 0; m < rank; ++m) {
          if (to_double(abs(coefficients(m))) >= kDependenceShare * share) group.push_back(pivots(m));
        }
      }
    }
    attempt.dependent_groups.push_back(std::move(group));
  }

  // Condition numbers: after = of W (= of R), before = of diag(w) A = Q R P^T S^-1 M^-1.
  attempt.condition_after = condition_of(singular_values_of<Work>(R));
  attempt.condition_retained = rank > 0 ? condition_of(singular_values_of<Work>(Matrix<Work>(R11))) : kInf;
  {
    Matrix<Work> before(p, p);
    for (Index l = 0; l < p; ++l) before.col(pivots(l)) = R.col(l);
    for (Index j = 0; j < p; ++j) before.col(j) /= Work(transform.scale[static_cast<std::size_t>(j)]);
    if (transform.centre_column >= 0) {
      const Vector<Work> centre = before.col(transform.centre_column);
      for (Index j = 0; j < p; ++j) {
        if (j != transform.centre_column) before.col(j) += static_cast<Work>(transform.shift[static_cast<std::size_t>(j)]) * centre;
      }
    }
    attempt.condition_before = condition_of(singular_values_of<Work>(before));
  }

  // Solve with the retained columns; u in work coordinates, pivoted entries beyond rank zero.
  const auto solve_pivoted = [&](const Vector<Work>& qt_rhs_head) {
    AccVector<Acc> u(p_size, Acc(0));
    if (rank == 0) return u;
    const Vector<Work> head = R11.solve(qt_rhs_head);
    for (Index l = 0; l < rank; ++l) u[static_cast<std::size_t>(pivots(l))] = Acc(head(l));
    return u;
  };
  Vector<Work> weighted_b(n);
  for (Index i = 0; i < n; ++i) weighted_b(i) = static_cast<Work>(Ext(rows.weight(i)) * Ext(rows.b(i)));
  const Vector<Work> qt_b = qr.householderQ().adjoint() * weighted_b;
  AccVector<Acc> u = solve_pivoted(qt_b.head(rank));
  AccVector<Acc> x = transform.to_original(u);
  const AccVector<Acc> x_initial = x;

  // Bjorck's refinement of [r; u]. The correction (dr, du) solves dr + W du = f, W^T dr = g:
  // with W P = Q R, h = R11^-T (P^T g)_head, d = Q^T f, du_piv = R11^-1 (d_head - h),
  // dr = Q [h; d_tail].
  if (refinement_steps > 0 && rank > 0) {
    AccVector<Acc> r(static_cast<std::size_t>(n));
    for (Index i = 0; i < n; ++i) {
      Acc fitted = 0;
      for (Index j = 0; j < p; ++j) fitted += Acc(rows.A(i, j)) * x[static_cast<std::size_t>(j)];
      r[static_cast<std::size_t>(i)] = Acc(rows.weight(i)) * (Acc(rows.b(i)) - fitted);
    }
    AccVector<Acc> f, g;
    for (int step = 0; step < refinement_steps; ++step) {
      augmented_residuals(rows, transform, x, r, f, g);
      Vector<Work> g_head(rank);
      for (Index l = 0; l < rank; ++l) g_head(l) = static_cast<Work>(g[static_cast<std::size_t>(pivots(l))]);
      const Vector<Work> h = R11.transpose().solve(g_head);
      Vector<Work> d(n);
      for (Index i = 0; i < n; ++i) d(i) = static_cast<Work>(f[static_cast<std::size_t>(i)]);
      d = qr.householderQ().adjoint() * d;
      const AccVector<Acc> du = solve_pivoted(d.head(rank) - h);
      Vector<Work> dr_rotated = d;
      dr_rotated.head(rank) = h;
      const Vector<Work> dr = qr.householderQ() * dr_rotated;
      for (std::size_t j = 0; j < p_size; ++j) u[j] += du[j];
      for (Index i = 0; i < n; ++i) r[static_cast<std::size_t>(i)] += Acc(dr(i));
      const AccVector<Acc> x_next = transform.to_original(u);
      bool converged = true;
      for (std::size_t j = 0; j < p_size; ++j) {
        if (magnitude(x_next[j] - x[j]) > Acc(kConvergedShareOfUlp * DBL_EPSILON) * magnitude(x_next[j])) converged = false;
      }
      x = x_next;
      ++attempt.refinement_steps_taken;
      if (converged) break;
    }
    // Componentwise: the largest relative move of a non-zero parameter.
    double change = 0;
    for (std::size_t j = 0; j < p_size; ++j) {
      if (x[j] != Acc(0)) change = std::max(change, to_double(magnitude((x[j] - x_initial[j]) / x[j])));
    }
    attempt.refinement_change = change;
  }
  attempt.x.resize(p_size);
  for (std::size_t j = 0; j < p_size; ++j) attempt.x[j] = to_double(x[j]);

  // (R^T R)^-1 mapped back: T = M S P [R11^-1; 0] (p x rank), covariance_unit = T T^T.
  ExtMatrix T = ExtMatrix::Zero(p, rank);
  if (rank > 0) {
    const Matrix<Work> R11_inverse = R11.solve(Matrix<Work>::Identity(rank, rank));
    for (Index m = 0; m < rank; ++m) {
      AccVector<Ext> column(p_size, Ext(0));
      for (Index l = 0; l < rank; ++l) column[static_cast<std::size_t>(pivots(l))] = Ext(R11_inverse(l, m));
      column = transform.to_original(column);
      for (Index j = 0; j < p; ++j) T(j, m) = column[static_cast<std::size_t>(j)];
    }
  }
  attempt.covariance_unit = T * T.transpose();
  for (Index j = 0; j < p; ++j) {
    if (!attempt.dropped[static_cast<std::size_t>(j)]) continue;
    attempt.covariance_unit.row(j).setConstant(Ext(kNaN));
    attempt.covariance_unit.col(j).setConstant(Ext(kNaN));
  }
  return attempt;
}

std::string format_row(std::size_t row) { return fmt::format("row {}", row + 1); }

// Step 1: sizes, finiteness, weights. Returns an empty string when the rows are acceptable.
std::string check_rows(const Rows& rows, const std::vector<std::string>& names) {
  const Index n = rows.n(), p = rows.p();
  if (p == 0) return "the design has no columns";
  if (names.size() != static_cast<std::size_t>(p)) {
    return fmt::format("{} column names for {} columns", names.size(), p);
  }
  if (rows.b.size() != n) return fmt::format("right-hand side has {} rows, design {}", rows.b.size(), n);
  if (rows.w && rows.w->size() != n) return fmt::format("{} weights for {} rows", rows.w->size(), n);
  if (!rows.A.allFinite()) {
    for (Index j = 0; j < p; ++j) {
      for (Index i = 0; i < n; ++i) {
        if (!std::isfinite(rows.A(i, j))) {
          return fmt::format("column `{}` is {} at {}", names[static_cast<std::size_t>(j)],
                             rows.A(i, j), format_row(static_cast<std::size_t>(i)));
        }
      }
    }
  }
  for (Index i = 0; i < n; ++i) {
    if (!std::isfinite(rows.b(i))) {
      return fmt::format("right-hand side is {} at {}", rows.b(i), format_row(static_cast<std::size_t>(i)));
    }
    if (rows.w && !(std::isfinite((*rows.w)(i)) && (*rows.w)(i) >= 0)) {
      return fmt::format("weight of {} is {} (weights must be finite and >= 0)",
                         format_row(static_cast<std::size_t>(i)), (*rows.w)(i));
    }
  }
  return {};
}

std::size_t rows_with_weight(const Rows& rows) {
  if (!rows.w) return static_cast<std::size_t>(rows.n());
  return static_cast<std::size_t>((rows.w->array() != 0.0).count());
}

// The first column that equals one non-zero constant on every row with non-zero weight.
struct ConstantColumn {
  int index = -1;  // -1: none
  double value = 0;
};

ConstantColumn constant_column_of(const Rows& rows) {
  for (Index j = 0; j < rows.p(); ++j) {
    double value = 0;
    bool constant = true, seen = false;
    for (Index i = 0; i < rows.n() && constant; ++i) {
      if (rows.weight(i) == 0) continue;
      if (!seen) {
        value = rows.A(i, j);
        seen = true;
      } else if (rows.A(i, j) != value) {
        constant = false;
      }
    }
    if (constant && seen && value != 0) return {static_cast<int>(j), value};
  }
  return {};
}

// The power of two 2^-e that brings `norm` = m 2^e (m in [0.5, 1)) into [0.5, 1); 1 for a zero or
// non-finite norm. e is kept where 2^-e is a normal double, so that the factor itself is finite and
// exact: a column of subnormal numbers (norm below 2^-1022) is scaled by 2^1022 and stays small,
// which the condition number then shows, rather than by an infinite factor that makes it NaN.
double power_of_two_scale(double norm) {
  if (!(norm > 0) || !std::isfinite(norm)) return 1.0;
  int exponent = 0;
  std::frexp(norm, &exponent);
  return std::ldexp(1.0, std::clamp(-exponent, -1022, 1022));
}

// Step 2: the column transform. Centring first (it changes the norms), then scaling.
ColumnTransform choose_transform(const Rows& rows, const LeastSquaresOptions& options, ConstantColumn constant) {
  const Index n = rows.n(), p = rows.p();
  ColumnTransform transform;
  transform.scale.assign(static_cast<std::size_t>(p), 1.0);
  transform.shift.assign(static_cast<std::size_t>(p), Ext(0));
  if (options.center_columns && constant.index >= 0) {
    // shift_j = (weighted mean of column j) / constant, weights w_i^2 as in G (eq. 2-1.7).
    transform.centre_column = constant.index;
    Ext weight_sum = 0;
    ExtVector weighted_sums = ExtVector::Zero(p);
    for (Index i = 0; i < n; ++i) {
      const Ext w2 = Ext(rows.weight(i)) * Ext(rows.weight(i));
      weight_sum += w2;
      for (Index j = 0; j < p; ++j) weighted_sums(j) += w2 * Ext(rows.A(i, j));
    }
    for (Index j = 0; j < p; ++j) {
      if (j == constant.index) continue;
      transform.shift[static_cast<std::size_t>(j)] = weighted_sums(j) / weight_sum / Ext(constant.value);
    }
  }
  if (options.scale_columns) {
    for (Index j = 0; j < p; ++j) {
      Ext sum = 0;
      for (Index i = 0; i < n; ++i) {
        const Ext entry = transform.work_entry(rows, i, j);  // scale is still 1 here
        sum += entry * entry;
      }
      using std::sqrt;
      transform.scale[static_cast<std::size_t>(j)] = power_of_two_scale(to_double(sqrt(sum)));
    }
  }
  return transform;
}

double t_quantile(double probability, double degrees_of_freedom) {
  if (!(degrees_of_freedom >= 1)) return kNaN;
  try {
    const boost::math::students_t_distribution<double> distribution(degrees_of_freedom);
    return boost::math::quantile(distribution, probability);
  } catch (...) {  // Boost.Math reports domain errors by throwing; a status is what we promise
    return kNaN;
  }
}

LeastSquaresSummary failed(LeastSquaresSummary::Termination termination, std::string message,
                           const std::vector<std::string>& names, std::size_t n, std::size_t p) {
  LeastSquaresSummary summary;
  summary.termination = termination;
  summary.message = std::move(message);
  summary.n = n;
  summary.p = p;
  for (const std::string& name : names) summary.parameters.push_back({name, kNaN, kNaN, kNaN, kNaN});
  summary.G = summary.standard_error = summary.residual_sd = summary.r_squared = kNaN;
  summary.centred_r_squared = summary.uncentred_r_squared = kNaN;
  summary.aic = summary.bic = kNaN;
  summary.condition_before = summary.condition_after = summary.digits_lost_estimate = kNaN;
  return summary;
}

// What the statistics need from rows that a TriangularSystem no longer has.
struct StreamedTotals {
  std::size_t rows = 0;
  double residual_sum_of_squares = 0;
  int constant_column = -1;
  double total_centred = 0, total_uncentred = 0;
};

LeastSquaresSummary solve_rows(const Rows& rows, const std::vector<std::string>& names,
                               const LeastSquaresOptions& options, const StreamedTotals* streamed) {
  using Termination = LeastSquaresSummary::Termination;
  const std::size_t p = static_cast<std::size_t>(rows.p());
  std::string why;
  if (!options.is_valid(&why)) return failed(Termination::invalid_input, "invalid options: " + why, names, 0, p);
  why = check_rows(rows, names);
  if (!why.empty()) return failed(Termination::invalid_input, why, names, 0, p);
  const std::size_t n = streamed ? streamed->rows : rows_with_weight(rows);
  if (n < p) {
    return failed(Termination::too_few_rows,
                  fmt::format("{} rows with non-zero weight for {} parameters", n, p), names, n, p);
  }

  const ConstantColumn constant = streamed ? ConstantColumn{} : constant_column_of(rows);
  const int constant_column = streamed ? streamed->constant_column : constant.index;
  const LeastSquaresOptions effective = [&] {
    LeastSquaresOptions copy = options;
    if (streamed) copy.center_columns = false;
    return copy;
  }();
  const ColumnTransform transform = choose_transform(rows, effective, constant);
  const double rank_tolerance =
      options.rank_tolerance > 0 ? options.rank_tolerance
                                 : DBL_EPSILON * static_cast<double>(std::max(n, p));

  // The known side scaled like the columns (section 3-2): by the power of two that brings |w.*b| into
  // [0.5, 1). The QR then sees numbers near 1 whatever the record's units, so data of 1e-300 or of
  // subnormal size lose no digits to underflow in Q^T b; the parameters are divided by the same
  // power of two afterwards, which is exact.
  Ext known_squares = 0;
  for (Index i = 0; i < rows.n(); ++i) known_squares += (Ext(rows.weight(i)) * Ext(rows.b(i))) * (Ext(rows.weight(i)) * Ext(rows.b(i)));
  using std::sqrt;
  const double known_scale = power_of_two_scale(to_double(sqrt(known_squares)));
  const Eigen::VectorXd scaled_b = rows.b * known_scale;
  const Rows scaled_rows{rows.A, scaled_b, rows.w};

  // Steps 3 and 4 in the chosen precision.
  const double work = static_cast<double>(rows.n()) * static_cast<double>(p) * static_cast<double>(p);
  const bool extended = options.precision == Precision::extended ||
                        (options.precision == Precision::automatic && work <= options.extended_work_limit);
  const Attempt attempt = extended ? fit_in<Ext, QuadScalar>(scaled_rows, transform, rank_tolerance, options.refinement_steps)
                                   : fit_in<double, Ext>(scaled_rows, transform, rank_tolerance, options.refinement_steps);
  std::string arithmetic =
      extended ? fmt::format("QR in {} ({} bits), refinement residuals in {}", kExtendedName, mantissa_bits<Ext>(), kQuadName)
               : fmt::format("QR in double, refinement residuals in {} ({} bits)", kExtendedName, mantissa_bits<Ext>());
  if (options.precision == Precision::automatic) {
    arithmetic += fmt::format(" (automatic: n*p^2 = {:.3g} {} {:.3g})", work, extended ? "<=" : ">",
                              options.extended_work_limit);
  }

  LeastSquaresSummary summary;
  summary.n = n;
  summary.p = p;
  summary.rank = attempt.rank;
  summary.extended_precision_used = extended;
  summary.arithmetic = arithmetic;
  summary.columns_scaled = options.scale_columns;
  summary.columns_centred = transform.centre_column >= 0;
  summary.refinement_steps_taken = attempt.refinement_steps_taken;
  summary.refinement_change = attempt.refinement_change;
  summary.rank_tolerance_used = rank_tolerance;
  summary.condition_before = attempt.condition_before;
  summary.condition_after = attempt.condition_after;
  summary.digits_lost_estimate = std::log10(attempt.condition_after);
  for (const auto& group : attempt.dependent_groups) {
    std::vector<std::string> named;
    for (Index j : group) named.push_back(names[static_cast<std::size_t>(j)]);
    summary.dependent_groups.push_back(std::move(named));
  }

  // Step 5: statistics of the reported parameters, against the original rows. Every sum of squares
  // and everything derived from one stays in the extended type (exponents to about +-4900) until
  // the end: a record of values near 1e200 or 1e-300 has G near 1e400 or 1e-600, beyond a double,
  // while its standard errors, R^2, AIC and BIC are ordinary numbers. Only G itself may then not be
  // representable (statistics_not_representable() names it).
  Eigen::VectorXd x(static_cast<Index>(p));
  for (Index j = 0; j < x.size(); ++j) x(j) = to_double(Ext(attempt.x[static_cast<std::size_t>(j)]) / Ext(known_scale));
  Ext G = 0, weight_sum = 0, weighted_b_sum = 0;
  const Index rows_n = rows.n();
  std::vector<Ext> fitted(static_cast<std::size_t>(rows_n));
  if (!streamed) summary.residuals.resize(static_cast<std::size_t>(rows_n));
  for (Index i = 0; i < rows_n; ++i) {
    Ext value = 0;
    for (Index j = 0; j < x.size(); ++j) value += Ext(rows.A(i, j)) * Ext(x(j));
    fitted[static_cast<std::size_t>(i)] = value;
    const Ext residual = Ext(rows.b(i)) - value;
    const Ext w = Ext(rows.weight(i));
    G += (w * residual) * (w * residual);
    weight_sum += w * w;
    weighted_b_sum += w * w * Ext(rows.b(i));
    if (!streamed) summary.residuals[static_cast<std::size_t>(i)] = to_double(residual);
  }
  const bool centred_r2 = options.intercept_in_r2 && constant_column >= 0;
  summary.r_squared_centred = centred_r2;
  Ext total_centred = 0, total_uncentred = 0;  // sum w^2 (b - ybar_w)^2 and sum (w b)^2
  if (streamed) {
    G += Ext(streamed->residual_sum_of_squares);
    total_centred = Ext(streamed->total_centred);
    total_uncentred = Ext(streamed->total_uncentred);
    const Ext total = centred_r2 ? total_centred : total_uncentred;
    summary.r_squared = total > Ext(0) ? to_double(Ext(1) - G / total) : kNaN;
  } else {
    const Ext mean = weight_sum > 0 ? weighted_b_sum / weight_sum : Ext(0);
    Ext explained = 0, centred = 0, uncentred = 0;
    for (Index i = 0; i < rows_n; ++i) {
      const Ext w = Ext(rows.weight(i));
      const Ext deviation = w * (fitted[static_cast<std::size_t>(i)] - (centred_r2 ? mean : Ext(0)));
      explained += deviation * deviation;
      centred += (w * (Ext(rows.b(i)) - mean)) * (w * (Ext(rows.b(i)) - mean));
      uncentred += (w * Ext(rows.b(i))) * (w * Ext(rows.b(i)));
    }
    summary.r_squared = explained + G > 0 ? to_double(explained / (explained + G)) : kNaN;
    total_centred = centred;
    total_uncentred = uncentred;
  }
  // The one not chosen as r_squared, as 1 - G / TSS (the chosen one keeps its SSR / (SSR + G) digits).
  const auto one_minus = [&](Ext total) { return total > Ext(0) ? to_double(Ext(1) - G / total) : kNaN; };
  summary.centred_r_squared = centred_r2 ? summary.r_squared : one_minus(total_centred);
  summary.uncentred_r_squared = centred_r2 ? one_minus(total_uncentred) : summary.r_squared;
  summary.G = to_double(G);
  using std::log;
  const double n_double = static_cast<double>(n);
  const double k = static_cast<double>(attempt.rank);
  const std::size_t dof = n - attempt.rank;
  summary.standard_error = n > 0 ? to_double(sqrt(G / Ext(n_double))) : kNaN;  // Table 4-1.2
  summary.residual_sd = dof > 0 ? to_double(sqrt(G / Ext(static_cast<double>(dof)))) : kNaN;
  const double log_mean_square = n > 0 && G > Ext(0) ? to_double(log(G / Ext(n_double)))
                                 : n > 0             ? -kInf
                                                     : kNaN;
  summary.aic = n_double * log_mean_square + 2 * k;
  summary.bic = n_double * log_mean_square + k * std::log(n_double);

  const Ext variance = dof > 0 ? G / Ext(static_cast<double>(dof)) : Ext(kNaN);
  const double t = t_quantile(0.5 + options.confidence_level / 2, static_cast<double>(dof));
  summary.covariance.resize(static_cast<Index>(p), static_cast<Index>(p));
  for (Index i = 0; i < summary.covariance.rows(); ++i) {
    for (Index j = 0; j < summary.covariance.cols(); ++j) {
      summary.covariance(i, j) = to_double(attempt.covariance_unit(i, j) * variance);
    }
  }
  for (std::size_t j = 0; j < p; ++j) {
    ParameterEstimate estimate;
    estimate.name = names[j];
    estimate.value = x(static_cast<Index>(j));
    // From the extended product: a covariance beyond a double (parameters near 1e200) still has
    // a representable square root.
    const Ext diagonal = attempt.covariance_unit(static_cast<Index>(j), static_cast<Index>(j)) * variance;
    estimate.standard_error = attempt.dropped[j] || !(diagonal >= Ext(0)) ? kNaN : to_double(sqrt(diagonal));
    estimate.ci_low = estimate.value - t * estimate.standard_error;
    estimate.ci_high = estimate.value + t * estimate.standard_error;
    summary.parameters.push_back(std::move(estimate));
  }

  if (attempt.rank < p) {
    summary.termination = Termination::rank_deficient;
    std::vector<std::string> parts;
    for (const auto& group : summary.dependent_groups) {
      if (group.size() == 1) {
        parts.push_back(fmt::format("`{}` is zero or negligible", group[0]));
      } else {
        std::string others;
        for (std::size_t m = 1; m < group.size(); ++m) others += fmt::format("{}`{}`", m > 1 ? ", " : "", group[m]);
        parts.push_back(fmt::format("`{}` depends on {}", group[0], others));
      }
    }
    std::string joined;
    for (const std::string& part : parts) joined += (joined.empty() ? "" : "; ") + part;
    summary.message = fmt::format("rank {} < {} columns: {}", attempt.rank, p, joined);
  } else {
    summary.termination = Termination::success;
  }
  return summary;
}

std::string format_number(double value) {
  if (std::isnan(value)) return "n/a";
  return fmt::format("{:.10g}", value);
}

}  // namespace

bool LeastSquaresOptions::is_valid(std::string* why) const {
  const auto fail = [&](std::string text) {
    if (why) *why = std::move(text);
    return false;
  };
  if (refinement_steps < 0 || refinement_steps > 100) return fail("refinement_steps must be in 0..100");
  if (!(rank_tolerance >= 0 && rank_tolerance < 1)) return fail("rank_tolerance must be in [0, 1)");
  if (!(confidence_level > 0 && confidence_level < 1)) return fail("confidence_level must be in (0, 1)");
  if (!(extended_work_limit >= 0)) return fail("extended_work_limit must be >= 0");
  return true;
}

std::vector<std::string> unrepresentable_statistics(const LeastSquaresSummary& summary) {
  std::vector<std::string> found;
  if (summary.termination != LeastSquaresSummary::Termination::success &&
      summary.termination != LeastSquaresSummary::Termination::rank_deficient)
    return found;
  const auto why = [](double value) { return std::isnan(value) ? std::string("NaN") : fmt::format("{}", value); };
  // G under- or overflows a double while sqrt(G/n), computed from the extended G, does not.
  if (summary.G == 0 && summary.standard_error > 0)
    found.push_back("G(a) = sum of squared residuals (below the smallest double, shown as 0)");
  else if (std::isinf(summary.G) && std::isfinite(summary.standard_error))
    found.push_back("G(a) = sum of squared residuals (above the largest double, shown as inf)");
  else if (!std::isfinite(summary.G))
    found.push_back(fmt::format("G(a) = sum of squared residuals ({})", why(summary.G)));
  const std::pair<const char*, double> statistics[] = {
      {"the standard error sqrt(G/n)", summary.standard_error}, {"the residual SD", summary.residual_sd},
      {"R^2", summary.r_squared}, {"AIC", summary.aic}, {"BIC", summary.bic}};
  for (const auto& [name, value] : statistics)
    if (!std::isfinite(value)) found.push_back(fmt::format("{} ({})", name, why(value)));
  for (const ParameterEstimate& estimate : summary.parameters) {
    if (std::isnan(estimate.value) && std::isnan(estimate.standard_error)) continue;  // dropped as dependent
    if (estimate.value == 0 && std::isnan(estimate.standard_error) && summary.rank < summary.p) continue;
    if (!std::isfinite(estimate.value)) found.push_back(fmt::format("`{}` ({})", estimate.name, why(estimate.value)));
    if (!std::isfinite(estimate.standard_error))
      found.push_back(fmt::format("the standard error of `{}` ({})", estimate.name, why(estimate.standard_error)));
  }
  return found;
}

const char* to_string(LeastSquaresSummary::Termination termination) {
  switch (termination) {
    case LeastSquaresSummary::Termination::success: return "success";
    case LeastSquaresSummary::Termination::rank_deficient: return "rank deficient";
    case LeastSquaresSummary::Termination::invalid_input: return "invalid input";
    case LeastSquaresSummary::Termination::too_few_rows: return "too few rows";
  }
  return "unknown";
}

const char* to_string(Precision precision) {
  switch (precision) {
    case Precision::automatic: return "automatic";
    case Precision::double_precision: return "double";
    case Precision::extended: return "extended";
  }
  return "unknown";
}

bool LeastSquaresSummary::is_solution_usable() const { return termination == Termination::success; }

std::string LeastSquaresSummary::brief_report() const {
  if (termination == Termination::invalid_input || termination == Termination::too_few_rows) {
    return fmt::format("least squares: {}: {}", to_string(termination), message);
  }
  std::string text = fmt::format(
      "least squares: {}, n = {}, p = {}, rank = {}, G = {:.6g}, residual SD = {:.6g}, condition {:.2g} "
      "(scaled; {:.2g} unscaled), ~{:.1f} digits at risk",
      to_string(termination), n, p, rank, G, residual_sd, condition_after, condition_before,
      digits_lost_estimate);
  if (termination == Termination::rank_deficient) text += "; " + message;
  return text;
}

std::string LeastSquaresSummary::full_report() const {
  std::string text;
  const auto line = [&](const std::string& label, const std::string& value) {
    text += fmt::format("  {:<30} {}\n", label, value);
  };
  text += "Least squares: QR with column pivoting (Householder), thesis eqs. 2-1.6 to 2-1.8\n";
  line("termination", message.empty() ? std::string(to_string(termination))
                                      : fmt::format("{}: {}", to_string(termination), message));
  if (termination == Termination::invalid_input || termination == Termination::too_few_rows) return text;
  line("rows n (non-zero weight)", fmt::format("{}", n));
  line("parameters p, rank", fmt::format("{}, {} (pivot tolerance {:.3g} x |R11|)", p, rank, rank_tolerance_used));
  line("column scaling (eq. 3-2.4)", columns_scaled ? "on (powers of two: exact)" : "off");
  line("column centring", columns_centred ? "on (on the constant column; mapped back exactly)" : "off");
  line("arithmetic", arithmetic);
  if (refinement_steps_taken > 0) {
    line("refinement", fmt::format("{} step(s) (Bjorck, augmented system); moved the plain QR solution by "
                                   "{:.2g} (largest relative change of a parameter)",
                                   refinement_steps_taken, refinement_change));
  } else {
    line("refinement", "off");
  }
  line("condition (2-norm)", fmt::format("{:.3g} before scaling, {:.3g} after", condition_before, condition_after));
  line("digits lost (estimate)", fmt::format("{:.1f} = log10(condition after); ~{:.1f} of 16 remain",
                                             digits_lost_estimate, std::max(0.0, 16 - digits_lost_estimate)));
  line("G = sum (w r)^2 (eq. 2-1.7)", format_number(G));
  line("standard error sqrt(G/n)", format_number(standard_error));
  line("residual SD sqrt(G/(n-rank))", format_number(residual_sd));
  line(r_squared_centred ? "R^2 (centred)" : "R^2 (uncentred)", format_number(r_squared));
  line(r_squared_centred ? "R^2 uncentred (beside it)" : "R^2 centred (beside it)",
       format_number(r_squared_centred ? uncentred_r_squared : centred_r_squared));
  line("AIC, BIC (n log(G/n) + ...)", format_number(aic) + ", " + format_number(bic));
  text += fmt::format("  {:<16} {:>18} {:>14} {:>18} {:>18}\n", "parameter", "estimate", "std. error",
                      "CI low", "CI high");
  for (const ParameterEstimate& estimate : parameters) {
    text += fmt::format("  {:<16} {:>18} {:>14} {:>18} {:>18}\n", estimate.name, format_number(estimate.value),
                        std::isnan(estimate.standard_error) ? std::string("n/a") : fmt::format("{:.6g}", estimate.standard_error),
                        format_number(estimate.ci_low), format_number(estimate.ci_high));
  }
  for (const auto& group : dependent_groups) {
    std::string names;
    for (std::size_t m = 1; m < group.size(); ++m) names += fmt::format("{}`{}`", m > 1 ? ", " : "", group[m]);
    text += group.size() == 1 ? fmt::format("  dependent: `{}` is zero or negligible\n", group[0])
                              : fmt::format("  dependent: `{}` ~ combination of {}\n", group[0], names);
  }
  return text;
}

LeastSquaresSummary solve_least_squares(const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
                                        const std::vector<std::string>& column_names,
                                        const Eigen::VectorXd* weights,
                                        const LeastSquaresOptions& options) {
  return solve_rows(Rows{A, b, weights}, column_names, options, nullptr);
}

std::optional<std::string> triangle_problem(const TriangularSystem& system) {
  const auto p = system.R.cols();
  if (system.R.rows() != p || system.z.size() != p)
    return fmt::format("the triangle is {} x {} with {} right-hand sides", system.R.rows(), p, system.z.size());
  if (!system.R.allFinite() || !system.z.allFinite() || !std::isfinite(system.residual_sum_of_squares))
    return std::string("the triangle has a NaN or infinite entry");
  if (system.residual_sum_of_squares < 0) return std::string("the triangle's residual sum of squares is negative");
  return std::nullopt;
}

LeastSquaresSummary solve_least_squares(const TriangularSystem& system,
                                        const std::vector<std::string>& column_names,
                                        const LeastSquaresOptions& options) {
  using Termination = LeastSquaresSummary::Termination;
  const Index p = system.R.cols();
  if (system.R.rows() != p || system.z.size() != p) {
    return failed(Termination::invalid_input, "triangular system is not p x p with p right-hand sides",
                  column_names, system.rows, static_cast<std::size_t>(p));
  }
  if (!std::isfinite(system.residual_sum_of_squares) || system.residual_sum_of_squares < 0) {
    return failed(Termination::invalid_input, "residual sum of squares of the triangular system is not finite",
                  column_names, system.rows, static_cast<std::size_t>(p));
  }
  StreamedTotals totals;
  totals.rows = system.rows;
  totals.residual_sum_of_squares = system.residual_sum_of_squares;
  totals.constant_column = system.constant_column;
  totals.total_centred = system.total_sum_of_squares_centred;
  totals.total_uncentred = system.total_sum_of_squares_uncentred;
  return solve_rows(Rows{system.R, system.z, nullptr}, column_names, options, &totals);
}

}  // namespace sidc
