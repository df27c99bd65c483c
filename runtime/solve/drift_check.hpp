// The drift check of an integrated fit: warns when an integrated equation's known side, or one of
// its operations, is on some record mostly a polynomial in time. Integrated k times (eqs. 2-1.4,
// 2-2.5), every mean or slow offset of the data grows like t^k; on a long window it swamps the
// part of the columns that tells the parameters apart, the estimates rest on what is left, and
// R^2 stays 1.000000 (uncentred). The case: a pendulum integrated twice over 10,000 s.
//
// Relies on: Eigen (small pivoted QRs). Guarantees: for equation e integrated k >= 1 times, on each
// record's rows of the design, the known side and each column that is not an integration
// constant get the share
//   1 - SS(residual on P_k) / SS(residual on P_(k-1)),
// where P_j is the polynomials of degree <= j in t together with the equation's columns that are
// exactly polynomials of degree <= k (a constant term integrated to `tau`, a step input: built
// that way, they absorb drift as the integration constants do). That is the part of what the
// constants (and such columns) can absorb that the t^k drift explains; for k = 1 and no such
// column, the variance explained by a straight line. Shares above kDriftWarningShare are findings; a
// column or known side that is itself exactly such a polynomial is none, and nor is any item when
// t^k is absorbed already. The warning's wording is diagnostics/model_catalogue.hpp's
// drift_dominates. Dense fits only (the streamed path keeps no rows); columns that are zero on an
// equation's rows (another equation's parameters) are skipped.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"
#include "runtime/solve/least_squares.hpp"

namespace sidc {

inline constexpr double kDriftWarningShare = 0.99;
inline constexpr double kExactPolynomial = 1e-12;

// 1 - SS_k / SS_(k-1): the residual sums of squares of `values` on [1, t, ..., t^degree] and on
// [1, ..., t^(degree-1)], both beside the columns of `absorbed` (rows as values; may have none).
// NaN when there are too few samples, when t^degree adds nothing to the span, or when nothing is
// left to explain beyond degree - 1.
double polynomial_share(std::span<const double> time, std::span<const double> values, int degree,
                        const Eigen::MatrixXd& absorbed = Eigen::MatrixXd());

// Whether `values` are a polynomial of degree <= `degree` in t to within kExactPolynomial of their
// sum of squares.
bool is_polynomial(std::span<const double> time, std::span<const double> values, int degree);

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
