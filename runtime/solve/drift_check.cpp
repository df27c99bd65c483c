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

namespace sidc {
namespace {

// Sum of squared residuals of the least-squares polynomial of `degree` in s (degree < 0: none).
double polynomial_residual(const Eigen::VectorXd& s, const Eigen::VectorXd& v, int degree) {
  if (degree < 0) return v.squaredNorm();
  Eigen::MatrixXd V(s.size(), degree + 1);
  V.col(0).setOnes();
  for (int k = 1; k <= degree; ++k) V.col(k) = V.col(k - 1).cwiseProduct(s);
  const Eigen::VectorXd c = V.colPivHouseholderQr().solve(v);
  return (v - V * c).squaredNorm();
}

}  // namespace

double polynomial_share(std::span<const double> time, std::span<const double> values, int degree) {
  const auto n = static_cast<Eigen::Index>(std::min(time.size(), values.size()));
  if (degree < 0 || n <= degree + 2) return std::numeric_limits<double>::quiet_NaN();
  const double first = time.front(), last = time[static_cast<std::size_t>(n - 1)];
  const double middle = 0.5 * (first + last), half = 0.5 * (last - first);
  if (!(half > 0)) return std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd s(n), v(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    s(i) = (time[static_cast<std::size_t>(i)] - middle) / half;  // on [-1, 1]: the monomials stay well conditioned
    v(i) = values[static_cast<std::size_t>(i)];
  }
  if (!v.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  const double lower = polynomial_residual(s, v, degree - 1), upper = polynomial_residual(s, v, degree);
  // Nothing left beyond degree k - 1 (rounding aside): an integration constant's own shape.
  if (!(lower > 1e-24 * std::max(v.squaredNorm(), std::numeric_limits<double>::min()))) return std::numeric_limits<double>::quiet_NaN();
  return std::clamp(1 - upper / lower, 0.0, 1.0);
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
      auto consider = [&](int item, const auto& value_of) {
        for (std::size_t i = 0; i < rows.size(); ++i) values[i] = value_of(rows[i]);
        const double share = polynomial_share(time, values, k);
        if (!std::isnan(share) && share > kDriftShare && (!largest.count(item) || share > largest[item].first)) largest[item] = {share, r};
      };
      consider(-1, [&](Eigen::Index i) { return b(i); });
      for (std::size_t c = 0; c < columns.size(); ++c) {
        const std::size_t p = column_parameters[c].parameter;
        if (p < model.parameters.size() && model.parameters[p].origin == ir::Parameter::Origin::integration_constant) continue;
        consider(static_cast<int>(c), [&](Eigen::Index i) { return A(i, static_cast<Eigen::Index>(c)); });
      }
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
