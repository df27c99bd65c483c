#include "runtime/solve/sliding_factor.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>

#include <Eigen/Core>

namespace sidc {
namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using Segment = Eigen::Map<Eigen::ArrayXd>;

}  // namespace

SlidingFactor::SlidingFactor(int p)
    : p_(p), R_(static_cast<std::size_t>(p) * static_cast<std::size_t>(p)), z_(static_cast<std::size_t>(p)),
      work_(static_cast<std::size_t>(p)), c_(static_cast<std::size_t>(p)), s_(static_cast<std::size_t>(p)) {}

void SlidingFactor::clear() {
  std::fill(R_.begin(), R_.end(), 0.0);
  std::fill(z_.begin(), z_.end(), 0.0);
  rho_ = 0;
  rho_lost_ = false;
}

// LINPACK dchud, row by row of R so that each rotation is one vectorised pass over a row.
void SlidingFactor::add(const double* x, double y) {
  std::copy(x, x + p_, work_.begin());
  for (int i = 0; i < p_; ++i) {
    const double xi = work_[static_cast<std::size_t>(i)];
    if (xi == 0) continue;
    const double h = std::hypot(r(i, i), xi), c = r(i, i) / h, s = xi / h;
    r(i, i) = h;
    const int rest = p_ - i - 1;
    if (rest > 0) {
      Segment row(&r(i, i + 1), rest), w(&work_[static_cast<std::size_t>(i) + 1], rest);
      const Eigen::ArrayXd t = c * row + s * w;
      w = c * w - s * row;
      row = t;
    }
    const double t = c * z_[static_cast<std::size_t>(i)] + s * y;
    y = c * y - s * z_[static_cast<std::size_t>(i)];
    z_[static_cast<std::size_t>(i)] = t;
  }
  if (!rho_lost_) rho_ = std::hypot(rho_, y);
}

// LINPACK dchdd (Saunders' downdate), R^-T x and the rotations applied row by row.
bool SlidingFactor::remove(const double* x, double y) {
  // a = R^-T x by forward substitution on R^T (column i of R^T is row i of R).
  std::copy(x, x + p_, work_.begin());
  double norm2 = 0;
  for (int i = 0; i < p_; ++i) {
    const double a = work_[static_cast<std::size_t>(i)] / r(i, i);
    work_[static_cast<std::size_t>(i)] = a;
    norm2 += a * a;
    const int rest = p_ - i - 1;
    if (rest > 0) Segment(&work_[static_cast<std::size_t>(i) + 1], rest) -= a * Segment(&r(i, i + 1), rest);
  }
  const double alpha2 = 1 - norm2;
  if (!(alpha2 >= kMinAlphaSquared)) return false;  // also NaN: a zero pivot
  double alpha = std::sqrt(alpha2);
  for (int i = p_ - 1; i >= 0; --i) {
    const double a = work_[static_cast<std::size_t>(i)], scale = alpha + std::abs(a);
    const double u = alpha / scale, v = a / scale, norm = std::sqrt(u * u + v * v);
    c_[static_cast<std::size_t>(i)] = u / norm;
    s_[static_cast<std::size_t>(i)] = v / norm;
    alpha = scale * norm;
  }
  // Column j meets the rotations i = j, j-1, ..., 0 with its own carry xx_j; row by row that is
  // i from p-1 down, every column j >= i at once.
  std::fill(work_.begin(), work_.end(), 0.0);
  for (int i = p_ - 1; i >= 0; --i) {
    const double c = c_[static_cast<std::size_t>(i)], s = s_[static_cast<std::size_t>(i)];
    const int count = p_ - i;
    Segment row(&r(i, i), count), xx(&work_[static_cast<std::size_t>(i)], count);
    const Eigen::ArrayXd t = c * xx + s * row;
    row = c * row - s * xx;
    xx = t;
  }
  double zeta = y;
  for (int i = 0; i < p_; ++i) {
    double& zi = z_[static_cast<std::size_t>(i)];
    zi = (zi - s_[static_cast<std::size_t>(i)] * zeta) / c_[static_cast<std::size_t>(i)];
    zeta = c_[static_cast<std::size_t>(i)] * zeta - s_[static_cast<std::size_t>(i)] * zi;
  }
  const double azeta = std::abs(zeta);
  if (azeta > rho_) {
    rho_lost_ = rho_lost_ || azeta > rho_ * (1 + 1e-8);  // beyond rounding: rho is not known any more
    rho_ = 0;
  } else if (rho_ > 0) {
    rho_ *= std::sqrt(std::max(0.0, 1 - (azeta / rho_) * (azeta / rho_)));
  }
  return true;
}

void SlidingFactor::scale(double factor) {
  for (double& v : R_) v *= factor;
  for (double& v : z_) v *= factor;
  rho_ *= factor;
}

SlidingSolution SlidingFactor::solve(double rows, double tolerance) const {
  SlidingSolution out;
  out.G = rho_ * rho_;
  const Eigen::Map<const RowMajor> R(R_.data(), p_, p_);
  const double tol = tolerance > 0 ? tolerance : DBL_EPSILON * std::max(rows, static_cast<double>(p_));
  // Column norms of R are those of the weighted design's columns (R^T R = A^T A).
  const Eigen::ArrayXd norms = R.triangularView<Eigen::Upper>().toDenseMatrix().colwise().norm().transpose().array();
  for (int j = 0; j < p_; ++j)
    if (norms(j) > 0 && std::abs(R(j, j)) > tol * norms(j)) ++out.rank;
  if (out.rank < p_) return out;
  const Eigen::Map<const Eigen::VectorXd> z(z_.data(), p_);
  const Eigen::VectorXd x = R.triangularView<Eigen::Upper>().solve(z);
  Eigen::MatrixXd inverse = Eigen::MatrixXd::Identity(p_, p_);
  R.triangularView<Eigen::Upper>().solveInPlace(inverse);
  // Cov = s^2 (R^T R)^-1 = s^2 R^-1 R^-T: the standard errors are s times the row norms of R^-1.
  const double dof = rows - p_;
  const double s = dof > 0 && !rho_lost_ ? rho_ / std::sqrt(dof) : std::nan("");
  out.estimates.assign(x.data(), x.data() + p_);
  out.standard_errors.resize(static_cast<std::size_t>(p_));
  for (int j = 0; j < p_; ++j) out.standard_errors[static_cast<std::size_t>(j)] = s * inverse.row(j).norm();
  if (rho_lost_) out.G = std::nan("");
  return out;
}

}  // namespace sidc
