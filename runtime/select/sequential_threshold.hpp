// Sequentially thresholded least squares (STLSQ), the sparse regression of SINDy (Brunton, Proctor
// & Kutz 2016), on a problem already reduced to a triangle: for many candidate operations, where
// exact best-subset search (best_subset.hpp) would take too long.
//
// Relies on: best_subset.hpp (solve_subset: least squares on some columns of a TriangularSystem).
// Nothing here sees the rows: every iteration costs O(p^3), whatever the number of samples.
//
// Method: fit all candidates; set to zero every free unit whose largest scaled coefficient is
// below the threshold; refit on what is left; repeat until the support stops changing (or
// max_iterations). The scaled coefficient of column j is u_j = x_j ||a_j|| / ||w b||: the share of
// the known side's norm the term carries, so one threshold means the same for every column
// whatever its units (||a_j|| is the norm of column j of R, equal to that of the weighted design
// column; ||w b||^2 = G(0) = ||z||^2 + rho^2).
//
// Guarantees: required columns are never removed; grouped columns leave together (a group goes
// when all its scaled coefficients are below the threshold); the path records the support and G
// after every fit, the first entry being the full model; the result is a fixed point (refitting the
// final support removes nothing) unless `converged` is false. Never throws; bad input comes back as
// invalid_input with a message.
#pragma once

#include <string>
#include <vector>

#include "runtime/select/best_subset.hpp"
#include "runtime/solve/least_squares.hpp"

namespace sidc {

struct SequentialThresholdOptions {
  double threshold = 0.05;  // on |u_j| (see the header), in (0, 1)
  std::vector<int> required;
  std::vector<std::vector<int>> groups;
  int max_iterations = 50;
  bool is_valid(int p, std::string* why) const;
};

struct ThresholdStep {
  std::vector<int> support;  // ascending columns fitted in this iteration
  double G = 0;
};

struct SequentialThresholdSummary {
  enum class Termination { success, invalid_input };
  Termination termination = Termination::invalid_input;
  std::string message;
  std::vector<ThresholdStep> path;   // support and G of each fit, the full model first
  std::vector<int> support;          // the final support
  std::vector<double> coefficients;  // length p, zero off the support
  std::vector<double> scaled;        // length p: the final |u_j| (0 off the support)
  double G = 0;
  bool converged = false;
};

SequentialThresholdSummary sequential_threshold(const TriangularSystem& system, const SequentialThresholdOptions& options);

// STLSQ for a sweep of thresholds (geometric from `smallest` to `largest`, `count` values): the
// best support found for every size, as best_subsets reports it (best[s] empty when no threshold
// gave a support of s columns). A heuristic: not the exact minimum per size.
std::vector<std::vector<SubsetFit>> threshold_sweep(const TriangularSystem& system, SequentialThresholdOptions options,
                                                    double smallest = 1e-4, double largest = 1.0, int count = 60);

}  // namespace sidc
