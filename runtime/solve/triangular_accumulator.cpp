// Streaming least squares by Householder QR of stacked triangles (see triangular_accumulator.hpp).
//
// Relies on: Eigen's HouseholderQR. Guarantees: the header's. The factor is of the augmented
// matrix [diag(w) A, diag(w) b], so its last diagonal entry rho carries the residual sum of
// squares of the least-squares solution of all rows folded so far (eq. 2-1.7) without the rows.
#include "runtime/solve/triangular_accumulator.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <fmt/format.h>

namespace sidc {

using Index = Eigen::Index;

TriangularAccumulator::TriangularAccumulator(int p)
    : p_(std::max(p, 0)),
      triangle_(Eigen::MatrixXd::Zero(p_ + 1, p_ + 1)),
      column_constant_(static_cast<std::size_t>(p_), 1),
      column_value_(static_cast<std::size_t>(p_), 0.0) {}

void TriangularAccumulator::fold(const Eigen::MatrixXd& weighted_rows) {
  const Index width = p_ + 1;
  Eigen::MatrixXd stacked(width + weighted_rows.rows(), width);
  stacked.topRows(width) = triangle_;
  stacked.bottomRows(weighted_rows.rows()) = weighted_rows;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(stacked);
  triangle_ = qr.matrixQR().topRows(width).triangularView<Eigen::Upper>();
}

void TriangularAccumulator::note_row(const Eigen::MatrixXd& block, const Eigen::VectorXd& rhs, Index i,
                                     double weight) {
  if (weight == 0) return;
  for (Index j = 0; j < p_; ++j) {
    const auto column = static_cast<std::size_t>(j);
    if (rows_ == 0) {
      column_value_[column] = block(i, j);
    } else if (block(i, j) != column_value_[column]) {
      column_constant_[column] = 0;
    }
  }
  ++rows_;
  // Welford's update with weight v = w^2 (the weight G gives the row).
  const long double v = static_cast<long double>(weight) * weight;
  const long double y = rhs(i);
  weight_sum_ += v;
  const long double delta = y - mean_;
  mean_ += delta * v / weight_sum_;
  centred_squares_ += v * delta * (y - mean_);
  uncentred_squares_ += v * y * y;
}

bool TriangularAccumulator::add_rows(const Eigen::MatrixXd& block, const Eigen::VectorXd& rhs,
                                     const Eigen::VectorXd* weights, std::string* why) {
  const auto reject = [&](std::string text) {
    ++rejected_blocks_;
    if (first_rejection_.empty()) first_rejection_ = text;
    if (why) *why = std::move(text);
    return false;
  };
  const Index m = block.rows();
  if (block.cols() != p_) return reject(fmt::format("block has {} columns, accumulator {}", block.cols(), p_));
  if (rhs.size() != m) return reject(fmt::format("block has {} rows but {} right-hand sides", m, rhs.size()));
  if (weights && weights->size() != m) return reject(fmt::format("block has {} rows but {} weights", m, weights->size()));
  if (!block.allFinite()) return reject("block has a NaN or infinite entry");
  if (!rhs.allFinite()) return reject("right-hand side has a NaN or infinite entry");
  if (weights && !(weights->allFinite() && (weights->array() >= 0).all())) {
    return reject("weights must be finite and >= 0");
  }

  for (Index start = 0; start < m; start += kRowsPerFold) {
    const Index count = std::min(kRowsPerFold, m - start);
    Eigen::MatrixXd weighted(count, p_ + 1);
    for (Index r = 0; r < count; ++r) {
      const Index i = start + r;
      const double w = weights ? (*weights)(i) : 1.0;
      weighted.row(r).head(p_) = w * block.row(i);
      weighted(r, p_) = w * rhs(i);
      note_row(block, rhs, i, w);
    }
    fold(weighted);
  }
  return true;
}

Eigen::Block<Eigen::MatrixXd> TriangularAccumulator::rows_area(Index m) {
  const Index width = p_ + 1;
  if (work_.rows() < width + m || work_.cols() != width) work_.resize(width + std::max<Index>(m, 0), width);
  return work_.block(width, 0, std::max<Index>(m, 0), width);
}

// Row totals of one block, combined with the running ones: the same quantities note_row keeps,
// per block with Chan et al.'s pairwise formula instead of per row with Welford's.
void TriangularAccumulator::note_block(const Eigen::Ref<const Eigen::MatrixXd>& rows, const double* weights) {
  const Index m = rows.rows();
  const auto b = rows.col(p_);
  std::size_t counted = 0;
  bool any_zero_weight = false;
  if (weights)
    for (Index i = 0; i < m; ++i) any_zero_weight |= weights[i] == 0;
  if (!any_zero_weight) {
    if (m == 0) return;
    for (Index j = 0; j < p_; ++j) {
      const auto column = static_cast<std::size_t>(j);
      if (rows_ == 0) column_value_[column] = rows(0, j);
      if (column_constant_[column] && !(rows.col(j).array() == column_value_[column]).all()) column_constant_[column] = 0;
    }
    counted = static_cast<std::size_t>(m);
  } else {
    for (Index i = 0; i < m; ++i) {
      if (weights[i] == 0) continue;
      for (Index j = 0; j < p_; ++j) {
        const auto column = static_cast<std::size_t>(j);
        if (rows_ == 0 && counted == 0) column_value_[column] = rows(i, j);
        else if (rows(i, j) != column_value_[column]) column_constant_[column] = 0;
      }
      ++counted;
    }
  }
  // Weighted moments of b with weights v = w^2: the block's own in double (two passes, so the
  // centred sum has no cancellation), then merged into the running long-double totals.
  double sum_v = static_cast<double>(m), block_mean = 0, block_centred = 0, sum_vyy = 0;
  if (!weights) {
    if (m > 0) block_mean = b.mean();
    block_centred = (b.array() - block_mean).square().sum();
    sum_vyy = b.squaredNorm();
  } else {
    const Eigen::ArrayXd v = Eigen::Map<const Eigen::ArrayXd>(weights, m).square();
    sum_v = v.sum();
    if (sum_v > 0) block_mean = (v * b.array()).sum() / sum_v;
    block_centred = (v * (b.array() - block_mean).square()).sum();
    sum_vyy = (v * b.array().square()).sum();
  }
  if (sum_v > 0) {
    const long double total = weight_sum_ + sum_v;
    const long double delta = block_mean - mean_;
    centred_squares_ += block_centred + delta * delta * weight_sum_ * sum_v / total;
    mean_ += delta * sum_v / total;
    weight_sum_ = total;
  }
  uncentred_squares_ += sum_vyy;
  rows_ += counted;
}

bool TriangularAccumulator::fold_rows_area(Index m, const double* weights, std::string* why) {
  const auto reject = [&](std::string text) {
    ++rejected_blocks_;
    if (first_rejection_.empty()) first_rejection_ = text;
    if (why) *why = std::move(text);
    return false;
  };
  const Index width = p_ + 1;
  if (m < 0 || work_.rows() < width + m || work_.cols() != width) return reject("fold_rows_area without a rows_area of that size");
  auto rows = work_.block(width, 0, m, width);
  if (!rows.leftCols(p_).allFinite()) return reject("block has a NaN or infinite entry");
  if (!rows.col(p_).allFinite()) return reject("right-hand side has a NaN or infinite entry");
  if (weights) {
    const Eigen::Map<const Eigen::VectorXd> w(weights, m);
    if (!(w.allFinite() && (w.array() >= 0).all())) return reject("weights must be finite and >= 0");
  }
  note_block(rows, weights);
  if (weights) rows = Eigen::Map<const Eigen::VectorXd>(weights, m).asDiagonal() * rows;
  // QR of the stacked [T; rows] in place: its R is the new T.
  work_.topRows(width) = triangle_;
  Eigen::Ref<Eigen::MatrixXd> stacked = work_.topRows(width + m);
  const Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(stacked);
  triangle_ = stacked.topRows(width).triangularView<Eigen::Upper>();
  return true;
}

bool TriangularAccumulator::merge(const TriangularAccumulator& other, std::string* why) {
  if (other.p_ != p_) {
    if (why) *why = fmt::format("cannot merge an accumulator of {} columns into one of {}", other.p_, p_);
    return false;
  }
  if (other.rows_ > 0) {
    for (std::size_t j = 0; j < column_constant_.size(); ++j) {
      if (rows_ == 0) {
        column_constant_[j] = other.column_constant_[j];
        column_value_[j] = other.column_value_[j];
      } else {
        column_constant_[j] = column_constant_[j] && other.column_constant_[j] && column_value_[j] == other.column_value_[j];
      }
    }
    // Chan et al.'s pairwise combination of weighted means and centred sums of squares.
    const long double total = weight_sum_ + other.weight_sum_;
    if (total > 0) {
      const long double delta = other.mean_ - mean_;
      centred_squares_ += other.centred_squares_ + delta * delta * weight_sum_ * other.weight_sum_ / total;
      mean_ += delta * other.weight_sum_ / total;
    }
    weight_sum_ = total;
    uncentred_squares_ += other.uncentred_squares_;
    rows_ += other.rows_;
    fold(other.triangle_);
  }
  rejected_blocks_ += other.rejected_blocks_;
  if (first_rejection_.empty()) first_rejection_ = other.first_rejection_;
  return true;
}

namespace {
void put_long(std::vector<double>& out, long double x) {
  const double hi = static_cast<double>(x);
  out.push_back(hi);
  out.push_back(static_cast<double>(x - hi));
}
long double get_long(const double*& p) {
  const long double x = static_cast<long double>(p[0]) + static_cast<long double>(p[1]);
  p += 2;
  return x;
}
}  // namespace

std::vector<double> TriangularAccumulator::to_doubles() const {
  std::vector<double> out;
  const auto width = static_cast<std::size_t>(p_ + 1);
  out.reserve(width * width + 2 * static_cast<std::size_t>(p_) + 11);
  out.push_back(static_cast<double>(p_));
  out.insert(out.end(), triangle_.data(), triangle_.data() + triangle_.size());
  out.push_back(static_cast<double>(rows_));  // exact below 2^53 rows
  out.push_back(static_cast<double>(rejected_blocks_));
  for (char c : column_constant_) out.push_back(c ? 1.0 : 0.0);
  out.insert(out.end(), column_value_.begin(), column_value_.end());
  for (long double x : {weight_sum_, mean_, centred_squares_, uncentred_squares_}) put_long(out, x);
  return out;
}

bool TriangularAccumulator::from_doubles(const std::vector<double>& state, std::string* why) {
  const auto width = static_cast<std::size_t>(p_ + 1);
  const std::size_t expected = 1 + width * width + 2 + 2 * static_cast<std::size_t>(p_) + 8;
  if (state.size() != expected || state[0] != static_cast<double>(p_)) {
    if (why) *why = fmt::format("an accumulator state of {} values for {} columns, expected {}", state.size(), state.empty() ? -1.0 : state[0], expected);
    return false;
  }
  const double* p = state.data() + 1;
  std::copy(p, p + width * width, triangle_.data());
  p += width * width;
  rows_ = static_cast<std::size_t>(*p++);
  rejected_blocks_ = static_cast<std::size_t>(*p++);
  for (auto& c : column_constant_) c = *p++ != 0.0 ? 1 : 0;
  for (auto& v : column_value_) v = *p++;
  weight_sum_ = get_long(p);
  mean_ = get_long(p);
  centred_squares_ = get_long(p);
  uncentred_squares_ = get_long(p);
  return true;
}

TriangularSystem TriangularAccumulator::system() const {
  TriangularSystem system;
  system.R = triangle_.topLeftCorner(p_, p_);
  system.z = triangle_.col(p_).head(p_);
  system.residual_sum_of_squares = triangle_(p_, p_) * triangle_(p_, p_);
  system.rows = rows_;
  for (int j = 0; j < p_ && rows_ > 0; ++j) {
    const auto column = static_cast<std::size_t>(j);
    if (column_constant_[column] && column_value_[column] != 0) {
      system.constant_column = j;
      break;
    }
  }
  system.total_sum_of_squares_centred = static_cast<double>(centred_squares_);
  system.total_sum_of_squares_uncentred = static_cast<double>(uncentred_squares_);
  return system;
}

LeastSquaresSummary TriangularAccumulator::solve(const std::vector<std::string>& column_names,
                                                 const LeastSquaresOptions& options) const {
  LeastSquaresSummary summary = solve_least_squares(system(), column_names, options);
  if (rejected_blocks_ > 0) {
    summary.termination = LeastSquaresSummary::Termination::invalid_input;
    summary.message = fmt::format("{} block(s) of rows were rejected and not fitted; the first: {}",
                                  rejected_blocks_, first_rejection_);
  }
  return summary;
}

Eigen::VectorXd TriangularAccumulator::residuals_of(const Eigen::MatrixXd& block, const Eigen::VectorXd& rhs,
                                                    const LeastSquaresSummary& summary) {
  Eigen::VectorXd residuals(block.rows());
  for (Index i = 0; i < block.rows(); ++i) {
    long double fitted = 0;
    for (Index j = 0; j < block.cols() && j < static_cast<Index>(summary.parameters.size()); ++j) {
      fitted += static_cast<long double>(block(i, j)) * summary.parameters[static_cast<std::size_t>(j)].value;
    }
    residuals(i) = static_cast<double>(static_cast<long double>(rhs(i)) - fitted);
  }
  return residuals;
}

}  // namespace sidc
