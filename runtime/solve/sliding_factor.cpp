#include "runtime/solve/sliding_factor.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>

namespace sidc {

SlidingFactor::SlidingFactor(int p)
    : p_(p), R_(static_cast<std::size_t>(p) * static_cast<std::size_t>(p)), z_(static_cast<std::size_t>(p)),
      work_(static_cast<std::size_t>(p)), c_(static_cast<std::size_t>(p)), s_(static_cast<std::size_t>(p)) {}

void SlidingFactor::clear() {
  std::fill(R_.begin(), R_.end(), 0.0);
  std::fill(z_.begin(), z_.end(), 0.0);
  rho_ = 0;
  rho_lost_ = false;
}

namespace {

// sqrt(a^2 + b^2) without hypot's cost; hypot where the squares would overflow or underflow.
double norm2(double a, double b) {
  const double h = std::sqrt(a * a + b * b);
  return std::isfinite(h) && h >= DBL_MIN * 0x1p60 ? h : std::hypot(a, b);
}

// The rotation [c s; -s c] applied to the pairs (u_j, w_j): u <- c u + s w, w <- c w - s u.
void rotate(double* u, double* w, int count, double c, double s) {
  for (int j = 0; j < count; ++j) {
    const double a = u[j], b = w[j];
    u[j] = c * a + s * b;
    w[j] = c * b - s * a;
  }
}

}  // namespace

// LINPACK dchud, row by row of R so that each rotation is one vectorised pass over a row.
void SlidingFactor::add(const double* x, double y) {
  std::copy(x, x + p_, work_.begin());
  double* w = work_.data();
  for (int i = 0; i < p_; ++i) {
    const double xi = w[i];
    if (xi == 0) continue;
    const double h = norm2(r(i, i), xi), c = r(i, i) / h, s = xi / h;
    r(i, i) = h;
    rotate(&r(i, i + 1), w + i + 1, p_ - i - 1, c, s);
    const double t = c * z_[static_cast<std::size_t>(i)] + s * y;
    y = c * y - s * z_[static_cast<std::size_t>(i)];
    z_[static_cast<std::size_t>(i)] = t;
  }
  if (!rho_lost_) rho_ = norm2(rho_, y);
}

// LINPACK dchdd (Saunders' downdate), R^-T x and the rotations applied row by row.
bool SlidingFactor::remove(const double* x, double y) {
  // a = R^-T x by forward substitution on R^T (column i of R^T is row i of R).
  std::copy(x, x + p_, work_.begin());
  double* w = work_.data();
  double norm = 0;
  for (int i = 0; i < p_; ++i) {
    const double a = w[i] / r(i, i);
    w[i] = a;
    norm += a * a;
    const double* row = &r(i, 0);
    for (int j = i + 1; j < p_; ++j) w[j] -= a * row[j];
  }
  const double alpha2 = 1 - norm;
  if (!(alpha2 >= kMinAlphaSquared)) return false;  // also NaN: a zero pivot
  double alpha = std::sqrt(alpha2);
  for (int i = p_ - 1; i >= 0; --i) {
    const double a = w[i], scale = alpha + std::abs(a);
    const double u = alpha / scale, v = a / scale, length = std::sqrt(u * u + v * v);
    c_[static_cast<std::size_t>(i)] = u / length;
    s_[static_cast<std::size_t>(i)] = v / length;
    alpha = scale * length;
  }
  // Column j meets the rotations i = j, j-1, ..., 0 with its own carry xx_j; row by row that is
  // i from p-1 down, every column j >= i at once: xx_j <- c xx_j + s R_ij, R_ij <- c R_ij - s xx_j.
  std::fill(work_.begin(), work_.end(), 0.0);
  for (int i = p_ - 1; i >= 0; --i) rotate(w + i, &r(i, i), p_ - i, c_[static_cast<std::size_t>(i)], s_[static_cast<std::size_t>(i)]);
  double zeta = y;
  for (int i = 0; i < p_; ++i) {
    double& zi = z_[static_cast<std::size_t>(i)];
    zi = (zi - s_[static_cast<std::size_t>(i)] * zeta) / c_[static_cast<std::size_t>(i)];
    zeta = c_[static_cast<std::size_t>(i)] * zeta - s_[static_cast<std::size_t>(i)] * zi;
  }
  // |zeta| > rho by rounding happens when the rows fit exactly (rho at rounding level): judged
  // against the size of the rows' known side, ||b||^2 = ||z||^2 + rho^2, not rho alone.
  const double azeta = std::abs(zeta);
  if (azeta > rho_) {
    double b2 = rho_ * rho_;
    for (double v : z_) b2 += v * v;
    rho_lost_ = rho_lost_ || azeta > rho_ + 64 * DBL_EPSILON * std::sqrt(b2);
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
  out.G = rho_lost_ ? std::nan("") : rho_ * rho_;
  const double tol = tolerance > 0 ? tolerance : DBL_EPSILON * std::max(rows, static_cast<double>(p_));
  // Column norms of R are those of the weighted design's columns (R^T R = A^T A).
  std::vector<double>& norms = scratch_;
  norms.assign(static_cast<std::size_t>(p_), 0.0);
  for (int i = 0; i < p_; ++i) {
    const double* row = this->row(i);
    for (int j = i; j < p_; ++j) norms[static_cast<std::size_t>(j)] += row[j] * row[j];
  }
  for (int j = 0; j < p_; ++j)
    if (norms[static_cast<std::size_t>(j)] > 0 && std::abs(r(j, j)) > tol * std::sqrt(norms[static_cast<std::size_t>(j)])) ++out.rank;
  if (out.rank < p_) return out;
  // x = R^-1 z, and the rows of R^-1 (upper triangular, row-major in inverse_), from the last up:
  // row i = (e_i - sum_{k>i} R_ik row k) / R_ii.
  out.estimates.resize(static_cast<std::size_t>(p_));
  std::vector<double>& inverse = inverse_;
  inverse.assign(R_.size(), 0.0);
  for (int i = p_ - 1; i >= 0; --i) {
    const double* row = this->row(i);
    double* inv = &inverse[static_cast<std::size_t>(i) * static_cast<std::size_t>(p_)];
    double xi = z_[static_cast<std::size_t>(i)];
    for (int k = i + 1; k < p_; ++k) {
      xi -= row[k] * out.estimates[static_cast<std::size_t>(k)];
      const double* below = &inverse[static_cast<std::size_t>(k) * static_cast<std::size_t>(p_)];
      const double f = row[k];
      for (int j = k; j < p_; ++j) inv[j] -= f * below[j];
    }
    const double d = 1 / row[i];
    out.estimates[static_cast<std::size_t>(i)] = xi * d;
    inv[i] = 1;
    for (int j = i; j < p_; ++j) inv[j] *= d;
  }
  // Cov = s^2 (R^T R)^-1 = s^2 R^-1 R^-T: the standard errors are s times the row norms of R^-1.
  const double dof = rows - p_;
  const double s = dof > 0 && !rho_lost_ ? rho_ / std::sqrt(dof) : std::nan("");
  out.standard_errors.resize(static_cast<std::size_t>(p_));
  for (int i = 0; i < p_; ++i) {
    const double* inv = &inverse[static_cast<std::size_t>(i) * static_cast<std::size_t>(p_)];
    double sum = 0;
    for (int j = i; j < p_; ++j) sum += inv[j] * inv[j];
    out.standard_errors[static_cast<std::size_t>(i)] = s * std::sqrt(sum);
  }
  return out;
}

}  // namespace sidc
