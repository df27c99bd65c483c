// The drift check of an integrated fit: warns when an integrated equation's known side, or one of
// its operations, is on some record mostly a polynomial in time. Integrated k times (eqs. 2-1.4,
// 2-2.5), every mean or slow offset of the data grows like t^k; on a long window it swamps the
// part of the columns that tells the parameters apart, the estimates rest on what is left, and
// R^2 stays 1.000000 (uncentred). The case: a pendulum integrated twice over 10,000 s.
//
// Relies on: Eigen (a small QR per column). Guarantees: for equation e integrated k >= 1 times, on
// each record's rows of the design, the known side and each column that is not an integration
// constant (those are the polynomials of degree < k on purpose) get the share
//   1 - SS(residual of the best polynomial of degree k) / SS(residual of degree k - 1),
// the part of what the integration constants can absorb (degree < k, or the mean when k = 1:
// then the share is the variance explained by a straight line) that the t^k drift explains.
// Shares above kDriftShare are findings; the warning's wording is
// diagnostics/model_catalogue.hpp's drift_dominates. Dense fits only (the streamed path keeps no
// rows); columns that are zero on an equation's rows (another equation's parameters) are skipped.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"
#include "runtime/solve/least_squares.hpp"

namespace sidc {

inline constexpr double kDriftShare = 0.99;

// 1 - SS_k / SS_(k-1) for the least-squares polynomials of degree k and k - 1 (degree -1: none,
// so k = 0 compares with 0) in t over the samples; NaN when there are too few samples or the
// values are a polynomial of degree k - 1 already (nothing left to explain).
double polynomial_share(std::span<const double> time, std::span<const double> values, int degree);

struct DriftFinding {
  std::size_t equation = 0;  // index into the model's equations
  std::string what;          // "known side" or the column's name
  std::string operation;     // the known side's or the column's operation, printed
  std::string record;        // where the share is largest
  int degree = 0;            // the equation's integrations
  double share = 0;          // the largest over records
};

// The drift findings of one dense group (fit.cpp): `A` and `b` its rows, unweighted, with
// `row_equation`, `row_record` and `row_time` per row as GroupFit keeps them.
std::vector<DriftFinding> find_drift(const ir::Model& model, const std::vector<std::size_t>& equations, const std::vector<std::string>& columns,
                                     const std::vector<ParameterIndex>& column_parameters, const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
                                     const std::vector<std::size_t>& row_equation, const std::vector<std::size_t>& row_record,
                                     const std::vector<double>& row_time, const std::vector<std::string>& record_paths);

// One warning per equation with findings: the known side's finding when there is one, else the
// largest, naming the others (diagnostics/model_catalogue.hpp, drift_dominates).
std::vector<Diagnostic> drift_warnings(const ir::Model& model, const std::vector<DriftFinding>& findings);

}  // namespace sidc
