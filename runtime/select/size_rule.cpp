// The relative-G elbow and the polynomial share of a column (see size_rule.hpp).
//
// Relies on: Eigen (HouseholderQR). Guarantees: the header's.
#include "runtime/select/size_rule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sidc {

ElbowResult relative_g_elbow(const std::vector<double>& G, double share) {
  ElbowResult result;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  result.left.assign(G.size(), nan);
  if (G.size() < 2) return result;
  // G = 0 (an exact fit) is held at the smallest normal number, so that logs stay finite.
  auto clamp = [](double g) { return std::max(g, std::numeric_limits<double>::min()); };
  // Differences of logs, not logs of ratios: G / G_full may overflow when G_full is near 0.
  const double floor = std::log(clamp(G.back()));
  for (std::size_t k = 1; k < G.size(); ++k) {
    const double before = std::log(clamp(G[k - 1])) - floor;
    const double after = std::max(0.0, std::log(clamp(G[k])) - floor);
    if (!(before > 0)) continue;
    result.left[k] = after / before;
    if (result.index < 0 && result.left[k] <= share) result.index = static_cast<int>(k);
  }
  // G never rises with size for the exact search; a heuristic's G may, and then no step need
  // close the distance: the largest size is the elbow (nothing is left after it).
  if (result.index < 0) result.index = static_cast<int>(G.size()) - 1;
  return result;
}

std::vector<double> polynomial_energy_share(const Eigen::Ref<const Eigen::MatrixXd>& values, int degree) {
  const Eigen::Index n = values.rows(), p = values.cols();
  std::vector<double> share(static_cast<std::size_t>(p), std::numeric_limits<double>::quiet_NaN());
  if (n == 0) return share;
  const Eigen::Index terms = std::min<Eigen::Index>(degree + 1, n);
  // Legendre polynomials of x in [-1, 1]: a well-conditioned basis of the same span as 1, t, ..., t^d.
  Eigen::MatrixXd basis(n, terms);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double x = n > 1 ? 2.0 * static_cast<double>(i) / static_cast<double>(n - 1) - 1.0 : 0.0;
    double previous = 1, current = x;
    basis(i, 0) = 1;
    if (terms > 1) basis(i, 1) = x;
    for (Eigen::Index j = 2; j < terms; ++j) {
      const double next = ((2.0 * static_cast<double>(j) - 1) * x * current - (static_cast<double>(j) - 1) * previous) / static_cast<double>(j);
      previous = current, current = next;
      basis(i, j) = next;
    }
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(basis);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(n, terms);
  for (Eigen::Index c = 0; c < p; ++c) {
    const Eigen::VectorXd v = values.col(c);
    const double total = v.squaredNorm();
    if (!(total > 0)) continue;  // the operation does not occur here (or is not finite)
    const double residual = (v - Q * (Q.transpose() * v)).squaredNorm();
    share[static_cast<std::size_t>(c)] = std::clamp(1.0 - residual / total, 0.0, 1.0);
  }
  return share;
}

std::vector<double> operation_line_share(const Eigen::Ref<const Eigen::MatrixXd>& values, int integrations) {
  Eigen::MatrixXd d = values;
  // The I-th forward difference undoes I integrations up to a constant factor h^I and a shift of
  // half a step per integration, neither of which changes the share.
  for (int i = 0; i < integrations && d.rows() > 0; ++i) d = (d.bottomRows(d.rows() - 1) - d.topRows(d.rows() - 1)).eval();
  return polynomial_energy_share(d, 1);
}

LineShareSums::LineShareSums(std::size_t rows, Eigen::Index p, int integrations)
    : n_(rows > static_cast<std::size_t>(integrations) ? rows - static_cast<std::size_t>(integrations) : 0),
      integrations_(integrations),
      head_(0, p),
      tail_(0, p),
      cross_(Eigen::MatrixXd::Zero(2, p)),
      squares_(Eigen::VectorXd::Zero(p)) {}

// The last `k` rows of [a; b].
static Eigen::MatrixXd last_rows(const Eigen::MatrixXd& a, const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Index k) {
  Eigen::MatrixXd both(a.rows() + b.rows(), a.cols());
  both << a, b;
  k = std::min(k, both.rows());
  return both.bottomRows(k);
}

void LineShareSums::accumulate(std::size_t first_level0, const Eigen::Ref<const Eigen::MatrixXd>& rows) {
  if (integrations_ == 0) return add_sums(first_level0, rows);
  work_ = rows;
  differences_in_work(first_level0);
}

// The I-th differences of the rows in work_, in place (v[i+1] - v[i], as operation_line_share
// takes them), into the sums.
void LineShareSums::differences_in_work(std::size_t first_level0) {
  Eigen::Index n = work_.rows();
  for (int level = 0; level < integrations_ && n > 0; ++level, --n)
    for (Eigen::Index c = 0; c < work_.cols(); ++c)
      for (Eigen::Index i = 0; i + 1 < n; ++i) work_(i, c) = work_(i + 1, c) - work_(i, c);
  add_sums(first_level0, work_.topRows(std::max<Eigen::Index>(n, 0)));
}

void LineShareSums::add_sums(std::size_t first, const Eigen::Ref<const Eigen::MatrixXd>& d) {
  if (d.rows() == 0) return;
  // polynomial_energy_share's abscissa of each differenced row.
  Eigen::VectorXd x(d.rows());
  for (Eigen::Index i = 0; i < d.rows(); ++i) {
    const auto k = static_cast<double>(first + static_cast<std::size_t>(i));
    x(i) = n_ > 1 ? 2.0 * k / static_cast<double>(n_ - 1) - 1.0 : 0.0;
  }
  gram_[0] += static_cast<double>(d.rows()), gram_[1] += x.sum(), gram_[2] += x.squaredNorm();
  cross_.row(0) += d.colwise().sum();
  cross_.row(1) += x.transpose() * d;
  squares_ += d.colwise().squaredNorm().transpose();
}

void LineShareSums::add(std::size_t first, const Eigen::Ref<const Eigen::MatrixXd>& block) {
  if (count_ == 0) first_ = first;
  const auto I = static_cast<Eigen::Index>(integrations_);
  if (I == 0) {
    add_sums(first, block);
    count_ += static_cast<std::size_t>(block.rows());
    return;
  }
  // [tail; block] in the work matrix (kept from call to call: no allocation per block).
  const Eigen::Index held = tail_.rows(), m = block.rows();
  work_.resize(held + m, block.cols());
  work_.topRows(held) = tail_;
  work_.bottomRows(m) = block;
  if (head_.rows() < I) head_ = work_.topRows(std::min(I, held + m));
  tail_ = work_.bottomRows(std::min(I, held + m));
  differences_in_work(first_ + count_ - static_cast<std::size_t>(held));
  count_ += static_cast<std::size_t>(m);
}

void LineShareSums::join(const LineShareSums& next) {
  if (next.count_ == 0) return;
  if (count_ == 0) {
    *this = next;
    return;
  }
  const auto I = static_cast<Eigen::Index>(integrations_);
  Eigen::MatrixXd stacked(tail_.rows() + next.head_.rows(), tail_.cols());
  stacked << tail_, next.head_;
  accumulate(first_ + count_ - static_cast<std::size_t>(tail_.rows()), stacked);  // the differences across the join
  for (int k = 0; k < 3; ++k) gram_[k] += next.gram_[k];
  cross_ += next.cross_;
  squares_ += next.squares_;
  if (head_.rows() < I) head_ = Eigen::MatrixXd(stacked.topRows(std::min(I, stacked.rows())));
  tail_ = last_rows(tail_, next.tail_, I);
  count_ += next.count_;
}

// n, integrations, first, count, p, head rows, tail rows, head, tail, gram, cross, squares.
std::vector<double> LineShareSums::to_doubles() const {
  std::vector<double> out{static_cast<double>(n_),          static_cast<double>(integrations_),  static_cast<double>(first_),
                          static_cast<double>(count_),      static_cast<double>(squares_.size()), static_cast<double>(head_.rows()),
                          static_cast<double>(tail_.rows())};
  out.insert(out.end(), head_.data(), head_.data() + head_.size());
  out.insert(out.end(), tail_.data(), tail_.data() + tail_.size());
  out.insert(out.end(), gram_, gram_ + 3);
  out.insert(out.end(), cross_.data(), cross_.data() + cross_.size());
  out.insert(out.end(), squares_.data(), squares_.data() + squares_.size());
  return out;
}

bool LineShareSums::from_doubles(const std::vector<double>& s) {
  if (s.size() < 7) return false;
  const auto p = static_cast<Eigen::Index>(s[4]), head = static_cast<Eigen::Index>(s[5]), tail = static_cast<Eigen::Index>(s[6]);
  if (p != squares_.size() || head < 0 || tail < 0 || s.size() != static_cast<std::size_t>(7 + (head + tail) * p + 3 + 3 * p)) return false;
  n_ = static_cast<std::size_t>(s[0]);
  integrations_ = static_cast<int>(s[1]);
  first_ = static_cast<std::size_t>(s[2]);
  count_ = static_cast<std::size_t>(s[3]);
  const double* at = s.data() + 7;
  head_ = Eigen::Map<const Eigen::MatrixXd>(at, head, p);
  at += head * p;
  tail_ = Eigen::Map<const Eigen::MatrixXd>(at, tail, p);
  at += tail * p;
  std::copy(at, at + 3, gram_);
  at += 3;
  cross_ = Eigen::Map<const Eigen::MatrixXd>(at, 2, p);
  at += 2 * p;
  squares_ = Eigen::Map<const Eigen::VectorXd>(at, p);
  return true;
}

std::vector<double> LineShareSums::shares() const {
  std::vector<double> share(static_cast<std::size_t>(squares_.size()), std::numeric_limits<double>::quiet_NaN());
  if (n_ == 0) return share;
  // The projection onto span(1, x): c^T G^-1 c; with one row the basis is the constant alone.
  const double det = gram_[0] * gram_[2] - gram_[1] * gram_[1];
  for (Eigen::Index c = 0; c < squares_.size(); ++c) {
    const double total = squares_(c);
    if (!(total > 0)) continue;  // the operation does not occur here (or is not finite)
    const double s0 = cross_(0, c), s1 = cross_(1, c);
    const double explained = n_ > 1 ? (gram_[2] * s0 * s0 - 2 * gram_[1] * s0 * s1 + gram_[0] * s1 * s1) / det : s0 * s0 / gram_[0];
    share[static_cast<std::size_t>(c)] = std::clamp(explained / total, 0.0, 1.0);
  }
  return share;
}

}  // namespace sidc
