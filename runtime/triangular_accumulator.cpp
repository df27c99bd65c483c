// Streaming least squares by Householder QR of stacked triangles (see triangular_accumulator.hpp).
//
// Relies on: Eigen's HouseholderQR. Guarantees: the header's. The factor is of the augmented
// matrix [diag(w) A, diag(w) b], so its last diagonal entry rho carries the residual sum of
// squares of the least-squares solution of all rows folded so far (eq. 2-1.7) without the rows.
#include "runtime/triangular_accumulator.hpp"

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
