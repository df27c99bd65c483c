// The Newey-West sandwich with AR(1) prewhitening and Andrews' bandwidth (see hac_covariance.hpp).
#include "runtime/solve/hac_covariance.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace sidc {

namespace {


struct ScoreSegment {
  Eigen::Index first = 0, rows = 0;
};

// sum over segments of sum_t x_t y_{t-lag}^T (rows of x and y are aligned with the segments).
Eigen::MatrixXd lagged_products(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, const std::vector<ScoreSegment>& segments, Eigen::Index lag) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(x.cols(), y.cols());
  for (const auto& s : segments)
    if (s.rows > lag) out.noalias() += x.middleRows(s.first + lag, s.rows - lag).transpose() * y.middleRows(s.first, s.rows - lag);
  return out;
}

// Bartlett-weighted long-run covariance of the rows of u: sum over |l| < S of (1 - |l|/S) Gamma_l.
Eigen::MatrixXd bartlett_sum(const Eigen::MatrixXd& u, const std::vector<ScoreSegment>& segments, double S) {
  Eigen::MatrixXd omega = lagged_products(u, u, segments, 0);
  for (Eigen::Index l = 1; static_cast<double>(l) < S; ++l) {
    const Eigen::MatrixXd gamma = lagged_products(u, u, segments, l);
    omega += (1.0 - static_cast<double>(l) / S) * (gamma + gamma.transpose());
  }
  return omega;
}

// Andrews (1991), eq. 6.4 with AR(1) models of each column and equal weights: the plug-in
// bandwidth of the Bartlett kernel, S = 1.1447 (alpha(1) T)^(1/3).
double andrews_bandwidth(const Eigen::MatrixXd& u, const std::vector<ScoreSegment>& segments, double T) {
  double numerator = 0, denominator = 0;
  for (Eigen::Index j = 0; j < u.cols(); ++j) {
    double xy = 0, xx = 0;
    for (const auto& s : segments)
      for (Eigen::Index t = s.first + 1; t < s.first + s.rows; ++t) {
        xy += u(t, j) * u(t - 1, j);
        xx += u(t - 1, j) * u(t - 1, j);
      }
    if (!(xx > 0)) continue;
    const double rho = std::clamp(xy / xx, -0.97, 0.97);
    double e2 = 0, count = 0;
    for (const auto& s : segments)
      for (Eigen::Index t = s.first + 1; t < s.first + s.rows; ++t) {
        const double e = u(t, j) - rho * u(t - 1, j);
        e2 += e * e;
        ++count;
      }
    const double s4 = (e2 / count) * (e2 / count);
    numerator += 4 * rho * rho * s4 / (std::pow(1 - rho, 6) * std::pow(1 + rho, 2));
    denominator += s4 / std::pow(1 - rho, 4);
  }
  if (!(denominator > 0)) return 1;
  return std::max(1.0, 1.1447 * std::cbrt(numerator / denominator * T));
}

std::vector<ScoreSegment> segments_of(const std::vector<std::size_t>& segment_starts, Eigen::Index n) {
  std::vector<ScoreSegment> segments;
  for (std::size_t k = 0; k < segment_starts.size(); ++k) {
    const auto first = static_cast<Eigen::Index>(segment_starts[k]);
    const Eigen::Index last = k + 1 < segment_starts.size() ? static_cast<Eigen::Index>(segment_starts[k + 1]) : n;
    if (last > first) segments.push_back({first, last - first});
  }
  return segments;
}

}  // namespace

// The lag-1 autocorrelation of e, each segment's mean removed, pooled over segments.
double lag1_autocorrelation(const std::vector<double>& e, const std::vector<std::size_t>& segment_starts) {
  const std::vector<ScoreSegment> segments = segments_of(segment_starts, static_cast<Eigen::Index>(e.size()));
  double c0 = 0, c1 = 0;
  for (const auto& s : segments) {
    double mean = 0;
    for (Eigen::Index t = s.first; t < s.first + s.rows; ++t) mean += e[static_cast<std::size_t>(t)];
    mean /= static_cast<double>(s.rows);
    for (Eigen::Index t = s.first; t < s.first + s.rows; ++t) {
      const double x = e[static_cast<std::size_t>(t)] - mean;
      c0 += x * x;
      if (t > s.first) c1 += x * (e[static_cast<std::size_t>(t - 1)] - mean);
    }
  }
  return c0 > 0 ? c1 / c0 : 0.0;
}

LongRunCovariance long_run_covariance(const Eigen::MatrixXd& raw_scores, const std::vector<std::size_t>& segment_starts, double max_work) {
  LongRunCovariance out;
  const Eigen::Index n = raw_scores.rows(), p = raw_scores.cols();
  const std::vector<ScoreSegment> segments = segments_of(segment_starts, n);
  if (segments.empty() || p == 0) {
    out.note = "no rows";
    return out;
  }
  const double T = static_cast<double>(n) / static_cast<double>(segments.size());  // rows per segment
  // A long-run covariance of p scores wants many rows per parameter: at 36 rows for 13 parameters
  // (the thesis' Table 4-1.3 fit) the estimate is noise.
  if (T < std::max(50.0, 10.0 * static_cast<double>(p))) {
    out.note = fmt::format("too few rows per record and equation ({:.0f}) for {} parameters", T, p);
    return out;
  }
  // Each column scaled to unit mean square (mapped back at the end).
  Eigen::VectorXd scale = (raw_scores.colwise().squaredNorm() / static_cast<double>(n)).cwiseSqrt().transpose();
  for (Eigen::Index j = 0; j < p; ++j)
    if (!(scale(j) > 0) || !std::isfinite(scale(j))) scale(j) = 1;
  const Eigen::MatrixXd scores = raw_scores * scale.cwiseInverse().asDiagonal();
  if (!scores.allFinite()) {
    out.note = "a score is not finite";
    return out;
  }

  // AR(1) prewhitening, column by column: u_t = s_t - rho s_{t-1}, |rho| at most 0.97. One
  // coefficient per column, not a p x p VAR: a VAR's p^2 coefficients from a few hundred rows
  // recolour by noise (measured on the thesis' 36-row, 13-parameter fit: ratios 0.66 to 2.1 on
  // white residuals).
  Eigen::VectorXd rho = Eigen::VectorXd::Zero(p);
  for (Eigen::Index j = 0; j < p; ++j) {
    double xy = 0, xx = 0;
    for (const auto& s : segments)
      for (Eigen::Index t = s.first + 1; t < s.first + s.rows; ++t) {
        xy += scores(t, j) * scores(t - 1, j);
        xx += scores(t - 1, j) * scores(t - 1, j);
      }
    rho(j) = xx > 0 ? xy / xx : 0.0;
    if (std::abs(rho(j)) > 0.97) {
      out.prewhitening_clamped = true;
      rho(j) = std::copysign(0.97, rho(j));
    }
  }
  // Whitened rows: each segment loses its first row.
  std::vector<ScoreSegment> whitened_segments;
  Eigen::MatrixXd u(n - static_cast<Eigen::Index>(segments.size()), p);
  Eigen::Index row = 0;
  for (const auto& s : segments) {
    const Eigen::Index m = s.rows - 1;
    if (m <= 0) continue;
    u.middleRows(row, m) = scores.middleRows(s.first + 1, m) - scores.middleRows(s.first, m) * rho.asDiagonal();
    whitened_segments.push_back({row, m});
    row += m;
  }
  u.conservativeResize(row, p);

  out.bandwidth = std::min(andrews_bandwidth(u, whitened_segments, T - 1), T - 1);
  if (static_cast<double>(n) * static_cast<double>(p * p) * out.bandwidth > max_work) {
    out.note = fmt::format("not computed: {} rows, {} parameters and {:.0f} lags are beyond its work limit", n, p, out.bandwidth);
    return out;
  }
  const Eigen::MatrixXd omega_u = bartlett_sum(u, whitened_segments, out.bandwidth);
  const Eigen::VectorXd recolour = (Eigen::VectorXd::Ones(p) - rho).cwiseInverse().cwiseProduct(scale);
  out.omega = recolour.asDiagonal() * omega_u * recolour.asDiagonal();
  out.computed = out.omega.allFinite();
  if (!out.computed) out.note = "the long-run covariance is not finite";
  return out;
}

HacEstimate hac_covariance(const Eigen::MatrixXd& A, const std::vector<double>& residuals, const Eigen::VectorXd* weights,
                           const std::vector<std::size_t>& segment_starts, const LeastSquaresSummary& summary, const HacOptions& options) {
  HacEstimate out;
  out.level = options.confidence_level;
  const Eigen::Index n = A.rows(), p = A.cols();
  if (!summary.is_solution_usable()) {
    out.note = "the fit is not usable";
    return out;
  }
  if (static_cast<Eigen::Index>(residuals.size()) != n || p == 0 || summary.parameters.size() != static_cast<std::size_t>(p) ||
      summary.covariance.rows() != p || !summary.covariance.allFinite() || !(summary.residual_sd > 0)) {
    out.note = "the classical covariance has no finite value to start from";
    return out;
  }
  // The scores s_i = w_i^2 r_i a_i, and the weighted residuals w_i r_i.
  Eigen::MatrixXd scores(n, p);
  std::vector<double> weighted(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    const double w = weights ? (*weights)(i) : 1.0;
    weighted[static_cast<std::size_t>(i)] = w * residuals[static_cast<std::size_t>(i)];
    scores.row(i) = (w * w * residuals[static_cast<std::size_t>(i)]) * A.row(i);
  }
  out.lag1_autocorrelation = lag1_autocorrelation(weighted, segment_starts);
  out.band = 2.576 / std::sqrt(static_cast<double>(n));
  const LongRunCovariance omega = long_run_covariance(scores, segment_starts, options.max_work);
  out.bandwidth = omega.bandwidth;
  out.prewhitening_clamped = omega.prewhitening_clamped;
  if (!omega.computed) {
    out.note = omega.note;
    return out;
  }
  const double dof = static_cast<double>(summary.n) - static_cast<double>(summary.rank);
  const double small_sample = dof > 0 ? static_cast<double>(n) / dof : 1.0;
  const double sigma2 = summary.residual_sd * summary.residual_sd;
  const Eigen::MatrixXd bread = summary.covariance / sigma2;  // (A^T W^2 A)^-1
  out.covariance = small_sample * (bread * omega.omega * bread);
  if (!out.covariance.allFinite()) {
    out.note = "the sandwich is not finite";
    return out;
  }
  out.computed = true;
  for (Eigen::Index j = 0; j < p; ++j) {
    const ParameterEstimate& c = summary.parameters[static_cast<std::size_t>(j)];
    const double se = std::sqrt(std::max(0.0, out.covariance(j, j)));
    // The classical interval's Student t quantile, read back from it.
    const double t = c.standard_error > 0 ? (c.ci_high - c.value) / c.standard_error : 1.959963984540054;
    out.standard_errors.push_back(se);
    out.ci_low.push_back(c.value - t * se);
    out.ci_high.push_back(c.value + t * se);
  }
  return out;
}

}  // namespace sidc
