// Unit tests of runtime/select/sequential_threshold.* (STLSQ) and runtime/select/forward_regression.* (FROLS):
// both must recover a known sparse model from a synthetic design, honour required columns and
// groups, and report a path that is consistent with independent least-squares fits.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "runtime/select/best_subset.hpp"
#include "runtime/select/forward_regression.hpp"
#include "runtime/select/sequential_threshold.hpp"
#include "runtime/solve/triangular_accumulator.hpp"

namespace sidc {
namespace {

struct Problem {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  TriangularSystem system;
};

// Columns of very different sizes (as operations are: y, y'^3, ...), a sparse truth, some noise.
Problem sparse_problem(int n, int p, const std::vector<std::pair<int, double>>& truth, double noise, unsigned seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> normal;
  Problem problem;
  problem.A.resize(n, p);
  for (int j = 0; j < p; ++j) {
    const double size = std::pow(10.0, (j % 5) - 2);
    for (int i = 0; i < n; ++i) problem.A(i, j) = size * normal(generator);
  }
  problem.b = Eigen::VectorXd::Zero(n);
  for (auto [c, v] : truth) problem.b += v * problem.A.col(c) / problem.A.col(c).norm() * std::sqrt(n);
  for (int i = 0; i < n; ++i) problem.b(i) += noise * normal(generator);
  TriangularAccumulator accumulator(p);
  EXPECT_TRUE(accumulator.add_rows(problem.A, problem.b, nullptr));
  problem.system = accumulator.system();
  return problem;
}

TEST(SequentialThreshold, RecoversSparseSupport) {
  const Problem problem = sparse_problem(300, 15, {{1, 1.0}, {6, -0.8}, {12, 0.5}}, 0.05, 1);
  SequentialThresholdOptions options;
  options.threshold = 0.1;
  const auto s = sequential_threshold(problem.system, options);
  ASSERT_EQ(s.termination, SequentialThresholdSummary::Termination::success) << s.message;
  EXPECT_TRUE(s.converged);
  EXPECT_EQ(s.support, (std::vector<int>{1, 6, 12}));
  ASSERT_GE(s.path.size(), 2u);
  EXPECT_EQ(s.path.front().support.size(), 15u);  // the full model first
  // Path G: each entry is the least-squares G of its support.
  for (const auto& step : s.path) EXPECT_NEAR(step.G, solve_subset(problem.system, step.support).G, 1e-9 * problem.b.squaredNorm());
  // The coefficients are those of least squares on the support, in the original units.
  const SubsetSolution direct = solve_subset(problem.system, s.support);
  for (std::size_t k = 0; k < s.support.size(); ++k)
    EXPECT_NEAR(s.coefficients[static_cast<std::size_t>(s.support[k])], direct.coefficients[k], 1e-9 * std::abs(direct.coefficients[k]));
}

TEST(SequentialThreshold, KeepsRequiredAndMovesGroupsTogether) {
  const Problem problem = sparse_problem(300, 10, {{1, 1.0}, {4, 0.7}}, 0.05, 2);
  SequentialThresholdOptions options;
  options.threshold = 0.1;
  options.required = {9};
  options.groups = {{4, 5}, {7, 8}};
  const auto s = sequential_threshold(problem.system, options);
  ASSERT_EQ(s.termination, SequentialThresholdSummary::Termination::success) << s.message;
  EXPECT_EQ(s.support, (std::vector<int>{1, 4, 5, 9}));
}

TEST(SequentialThreshold, SweepFindsTheTrueSupportAtItsSize) {
  const Problem problem = sparse_problem(300, 12, {{0, 1.0}, {3, 1.0}, {8, -0.6}}, 0.05, 3);
  const auto best = threshold_sweep(problem.system, {});
  ASSERT_FALSE(best[3].empty());
  EXPECT_EQ(best[3].front().columns, (std::vector<int>{0, 3, 8}));
}

TEST(SequentialThreshold, RejectsBadThreshold) {
  const Problem problem = sparse_problem(50, 4, {{0, 1.0}}, 0.1, 4);
  SequentialThresholdOptions options;
  options.threshold = 0;
  EXPECT_EQ(sequential_threshold(problem.system, options).termination, SequentialThresholdSummary::Termination::invalid_input);
}

TEST(ForwardRegression, EntersTheTrueTermsFirstWithConsistentErr) {
  const Problem problem = sparse_problem(300, 15, {{2, 1.0}, {7, -0.8}, {11, 0.5}}, 0.05, 5);
  const auto s = forward_regression(problem.system, {});
  ASSERT_EQ(s.termination, ForwardRegressionSummary::Termination::success) << s.message;
  ASSERT_EQ(s.steps.size(), 15u);
  std::vector<int> first;
  for (int k = 0; k < 3; ++k) first.push_back(s.steps[static_cast<std::size_t>(k)].entered.front());
  std::sort(first.begin(), first.end());
  EXPECT_EQ(first, (std::vector<int>{2, 7, 11}));
  EXPECT_GT(s.steps[2].cumulative_err, 0.99);
  // ERR adds up to the cumulative ERR, which is 1 - G/G(0), G that of least squares on the terms so far.
  double sum = 0;
  std::vector<int> so_far;
  for (const auto& step : s.steps) {
    sum += step.err;
    EXPECT_NEAR(step.cumulative_err, sum, 1e-12);
    so_far.insert(so_far.end(), step.entered.begin(), step.entered.end());
    EXPECT_NEAR(step.G, solve_subset(problem.system, so_far).G, 1e-9 * s.G_empty);
    EXPECT_NEAR(step.cumulative_err, 1 - step.G / s.G_empty, 1e-12);
  }
  EXPECT_LT(s.steps[3].err, 1e-3);  // what follows the true terms is noise
}

TEST(ForwardRegression, RequiredFirstGroupsTogetherAndMaxTerms) {
  const Problem problem = sparse_problem(300, 10, {{1, 1.0}, {4, 0.7}, {5, 0.2}}, 0.05, 6);
  ForwardRegressionOptions options;
  options.required = {9};
  options.groups = {{4, 5}};
  options.max_terms = 4;
  const auto s = forward_regression(problem.system, options);
  ASSERT_EQ(s.termination, ForwardRegressionSummary::Termination::success) << s.message;
  ASSERT_EQ(s.steps.size(), 3u);
  EXPECT_TRUE(s.steps[0].required);
  EXPECT_EQ(s.steps[0].entered, (std::vector<int>{9}));
  EXPECT_EQ(s.steps[1].entered, (std::vector<int>{1}));
  EXPECT_EQ(s.steps[2].entered, (std::vector<int>{4, 5}));
}

}  // namespace
}  // namespace sidc
