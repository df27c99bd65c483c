// The drift check (see drift_check.hpp): per integrated equation and record, the share of the
// known side and of each column that the degree-k polynomial in t explains beyond degree k - 1.
#include "runtime/solve/drift_check.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <fmt/format.h>
#include <cmath>
#include <limits>
#include <map>

#include "diagnostics/model_catalogue.hpp"
#include "ir/print.hpp"
#include "runtime/not_a_number.hpp"

namespace sidc {
namespace {

struct Fit {
  double residual = 0;  // sum of squares
  Eigen::Index rank = 0;
};

// The least-squares fit of v on the columns of V (scaled to unit norm first; rank by pivoted QR).
Fit fit_on(Eigen::MatrixXd V, const Eigen::VectorXd& v) {
  if (V.cols() == 0) return {v.squaredNorm(), 0};
  for (Eigen::Index k = 0; k < V.cols(); ++k)
    if (const double norm = V.col(k).norm(); norm > 0) V.col(k) /= norm;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(V);
  qr.setThreshold(1e-10);
  return {(v - V * qr.solve(v)).squaredNorm(), qr.rank()};
}

// [1, s, ..., s^degree] beside `absorbed`.
Eigen::MatrixXd basis(const Eigen::VectorXd& s, int degree, const Eigen::MatrixXd& absorbed) {
  Eigen::MatrixXd V(s.size(), std::max(degree + 1, 0) + absorbed.cols());
  for (int k = 0; k <= degree; ++k) V.col(k) = k == 0 ? Eigen::VectorXd::Ones(s.size()) : Eigen::VectorXd(V.col(k - 1).cwiseProduct(s));
  if (absorbed.cols() > 0) V.rightCols(absorbed.cols()) = absorbed;  // a 0 x 0 "none" cannot be assigned to n x 0
  return V;
}

}  // namespace

double polynomial_share(std::span<const double> time, std::span<const double> values, int degree, const Eigen::MatrixXd& absorbed) {
  const auto n = static_cast<Eigen::Index>(std::min(time.size(), values.size()));
  if (degree < 0 || n <= degree + 2 + absorbed.cols() || (absorbed.cols() && absorbed.rows() != n)) return kNaN;
  const double first = time.front(), last = time[static_cast<std::size_t>(n - 1)];
  const double middle = 0.5 * (first + last), half = 0.5 * (last - first);
  if (!(half > 0)) return kNaN;
  Eigen::VectorXd s(n), v(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    s(i) = (time[static_cast<std::size_t>(i)] - middle) / half;  // on [-1, 1]: the monomials stay well conditioned
    v(i) = values[static_cast<std::size_t>(i)];
  }
  if (!v.allFinite() || !absorbed.allFinite()) return kNaN;
  const Fit lower = fit_on(basis(s, degree - 1, absorbed), v), upper = fit_on(basis(s, degree, absorbed), v);
  if (upper.rank == lower.rank) return kNaN;  // t^k is absorbed already (an operation that is a polynomial)
  // Nothing left beyond what is absorbed (rounding aside): an integration constant's own shape.
  if (!(lower.residual > 1e-24 * std::max(v.squaredNorm(), std::numeric_limits<double>::min()))) return kNaN;
  return std::clamp(1 - upper.residual / lower.residual, 0.0, 1.0);
}

bool is_polynomial(std::span<const double> time, std::span<const double> values, int degree) {
  const auto n = static_cast<Eigen::Index>(std::min(time.size(), values.size()));
  if (n <= degree + 1 || !(time[static_cast<std::size_t>(n - 1)] > time.front())) return false;
  Eigen::VectorXd s(n), v(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    s(i) = 2 * (time[static_cast<std::size_t>(i)] - time.front()) / (time[static_cast<std::size_t>(n - 1)] - time.front()) - 1;
    v(i) = values[static_cast<std::size_t>(i)];
  }
  if (!v.allFinite() || v.squaredNorm() == 0) return false;
  return fit_on(basis(s, degree, Eigen::MatrixXd(n, 0)), v).residual <= kExactPolynomial * v.squaredNorm();
}

std::vector<DriftFinding> find_drift(const ir::Model& model, const std::vector<std::size_t>& equations, const std::vector<std::string>& columns,
                                     const std::vector<ParameterIndex>& column_parameters, const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
                                     const std::vector<std::size_t>& row_equation, const std::vector<std::size_t>& row_record,
                                     const std::vector<double>& row_time, const std::vector<std::string>& record_paths) {
  std::vector<DriftFinding> findings;
  for (std::size_t e : equations) {
    const ir::Equation& equation = model.equations[e];
    const int k = equation.integrations;
    if (k < 1) continue;
    // Per item (-1: the known side, else a column), the largest share over records and where.
    std::map<int, std::pair<double, std::size_t>> largest;
    for (std::size_t r = 0; r < record_paths.size(); ++r) {
      std::vector<Eigen::Index> rows;
      for (std::size_t i = 0; i < row_equation.size(); ++i)
        if (row_equation[i] == e && row_record[i] == r) rows.push_back(static_cast<Eigen::Index>(i));
      if (rows.empty()) continue;
      std::vector<double> time, values(rows.size());
      for (Eigen::Index i : rows) time.push_back(row_time[static_cast<std::size_t>(i)]);
      // Columns that are polynomials in t of degree <= k by construction (a constant term integrated
      // to tau, a step input) absorb drift of their degree as the integration constants do, and
      // are no drift themselves: they join the polynomials the shares are measured beyond.
      std::vector<std::size_t> checked;
      std::vector<Eigen::VectorXd> absorbing;
      for (std::size_t c = 0; c < columns.size(); ++c) {
        const std::size_t p = column_parameters[c].parameter;
        if (p < model.parameters.size() && model.parameters[p].origin == ir::Parameter::Origin::integration_constant) continue;
        Eigen::VectorXd column(static_cast<Eigen::Index>(rows.size()));
        for (std::size_t i = 0; i < rows.size(); ++i) column(static_cast<Eigen::Index>(i)) = A(rows[i], static_cast<Eigen::Index>(c));
        if (is_polynomial(time, std::span<const double>(column.data(), rows.size()), k)) absorbing.push_back(column);
        else checked.push_back(c);
      }
      Eigen::MatrixXd absorbed(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(absorbing.size()));
      for (std::size_t a = 0; a < absorbing.size(); ++a) absorbed.col(static_cast<Eigen::Index>(a)) = absorbing[a];
      auto consider = [&](int item, const auto& value_of) {
        for (std::size_t i = 0; i < rows.size(); ++i) values[i] = value_of(rows[i]);
        const double share = polynomial_share(time, values, k, absorbed);
        if (std::isnan(share) || share <= kDriftWarningShare) return;
        if (!largest.count(item) || share > largest[item].first) largest[item] = {share, r};
      };
      // A known side that is exactly such a polynomial (a step input integrated) is built that way too.
      for (std::size_t i = 0; i < rows.size(); ++i) values[i] = b(rows[i]);
      if (!is_polynomial(time, values, k)) consider(-1, [&](Eigen::Index i) { return b(i); });
      for (std::size_t c : checked) consider(static_cast<int>(c), [&](Eigen::Index i) { return A(i, static_cast<Eigen::Index>(c)); });
    }
    for (const auto& [item, found] : largest) {
      DriftFinding f;
      f.equation = e;
      f.degree = k;
      f.share = found.first;
      f.record = record_paths[found.second];
      if (item < 0) {
        f.what = "known side";
        f.operation = print(equation.known);
      } else {
        f.what = columns[static_cast<std::size_t>(item)];
        const std::size_t p = column_parameters[static_cast<std::size_t>(item)].parameter;
        for (const auto& term : equation.terms)
          if (static_cast<std::size_t>(term.parameter) == p) f.operation = print(term.operation);
      }
      findings.push_back(std::move(f));
    }
  }
  return findings;
}

std::vector<Diagnostic> drift_warnings(const ir::Model& model, const std::vector<DriftFinding>& findings) {
  std::vector<Diagnostic> warnings;
  std::map<std::size_t, std::vector<const DriftFinding*>> by_equation;
  for (const auto& f : findings) by_equation[f.equation].push_back(&f);
  for (const auto& [e, list] : by_equation) {
    // The known side first (it is what every parameter has to reproduce), else the largest share.
    const DriftFinding* main = list.front();
    for (const DriftFinding* f : list)
      if (main->what != "known side" && (f->what == "known side" || f->share > main->share)) main = f;
    std::string others;
    std::size_t count = 0;
    for (const DriftFinding* f : list)
      if (f != main) others += fmt::format("{}`{}`", count++ ? ", " : "", f->what == "known side" ? print(model.equations[e].known) : f->what);
    if (count) others = fmt::format("as {} the operation{} of {}", count == 1 ? "is" : "are", count == 1 ? "" : "s", others);
    const std::string what = main->what == "known side" ? fmt::format("its known side `{}`", main->operation)
                                                        : fmt::format("the operation of `{}` (`{}`)", main->what, main->operation);
    warnings.push_back(diag::drift_dominates(model.equations[e].span, e + 1, main->degree, what, main->record, main->share, others));
  }
  return warnings;
}

}  // namespace sidc
