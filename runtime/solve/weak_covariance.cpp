// Iterated generalised least squares for the weak form (see weak_covariance.hpp).
#include "runtime/solve/weak_covariance.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <fmt/format.h>

#include "ir/differentiate.hpp"
#include "ir/print.hpp"
#include "ir/queries.hpp"
#include "ir/traversal.hpp"
#include "runtime/operators/test_functions.hpp"

namespace sidc {
namespace {

// The iteration stops when no estimate moves by more than this share of the largest: far below
// the digits a report prints, far above rounding. WENDy's own tests settle in 5 to 15 solves.
constexpr double kSettled = 1e-9;
constexpr int kMostSolves = 30;
// The weighting rests on the noise explaining the residuals: whitened, their variance is then
// about 1. Above 4 (residuals more than twice what the noise levels explain) something else
// dominates them, a term the model lacks or the discretisation of a noise-free record, and a
// metric made from the noise alone would weight the rows by the wrong thing.
constexpr double kMostResidualVariance = 4.0;

// d/ds of the part of one sum (an operation or a known side) that phi^(k) multiplies, for one
// order k and one noisy signal s.
struct Sensitivity {
  int order = 0;
  std::string signal;
  std::optional<std::size_t> column;  // the operation's column; none for the known side
  ir::Sum derivative;
};

// Per equation of the group and record: every non-zero sensitivity, or why there is none to write.
std::variant<std::vector<Sensitivity>, std::string> sensitivities(const ir::Model& model, const DesignBuilder& design, std::size_t equation,
                                                                  std::size_t record, const NoiseBySignal& noise) {
  std::vector<Sensitivity> out;
  // Adds one sum's sensitivities; says why when there is none to write.
  const auto add = [&](const ir::Sum& sum, std::optional<std::size_t> column) -> std::optional<std::string> {
    for (const auto& [k, g] : parts_by_test_function(sum)) {
      for (const auto& level : noise) {
        const std::string& signal = level.first;  // named, not bound: lambdas below capture it
        if (!(level.second > 0)) continue;
        int highest = -1;
        ir::for_each_factor(g, [&](const ir::Factor& f) {
          if (f.kind == ir::FactorKind::signal && f.name == signal) highest = std::max(highest, f.order);
        });
        if (highest < 0) continue;
        // A switch on a noisy signal (a guard, sign()) flips where the noise crosses it: not a
        // first-order effect, so no covariance of first order describes it.
        const ir::Factor* noisy_switch = nullptr;
        ir::for_each_factor(g, [&](const ir::Factor& f) {
          if (!is_switch(f) || noisy_switch) return;
          ir::Sum inside = f.argument ? *f.argument : ir::Sum{};
          for (const auto& c : f.conditions) inside = ir::add(ir::add(inside, *c.lhs), *c.rhs);
          if (ir::any_factor(inside, [&](const ir::Factor& x) { return x.kind == ir::FactorKind::signal && x.name == signal; }))
            noisy_switch = &f;
        });
        if (noisy_switch) return fmt::format("`{}` switches on the noisy signal `{}`", print(*noisy_switch), signal);
        // Noise that reaches a row through a moving arc's stencil is not white per sample: not written here.
        for (int o = 0; o <= highest; ++o) {
          auto d = partial_derivative(g, signal, o);
          if (!d) return fmt::format("an int() or der() of `{}` in `{}`", signal, print(g));
          if (o > 0 && !d->terms.empty())
            return fmt::format("`{}`, a derivative estimated from the data, in `{}`",
                               print(ir::Factor{ir::FactorKind::signal, signal, o, {}, {}, {}, {}}), print(g));
          if (o == 0 && !d->terms.empty()) out.push_back({k, signal, column, std::move(*d)});
        }
      }
    }
    return std::nullopt;
  };
  const ir::Equation& eq = model.equations[equation];
  for (const auto& term : eq.terms)
    if (auto why = add(term.operation, design.column(term.parameter, record))) return *why;
  if (auto why = add(eq.known, std::nullopt)) return *why;
  return out;
}

// The rows' covariance C(x) over every record (block diagonal: records' noises are independent),
// rows laid out as weak_design() lays them: record by record, equation by equation, subdomain by
// subdomain. Entries are accumulated in a fixed order, so the result is the same on every run.
struct RowCovariance {
  const std::vector<std::vector<std::vector<Sensitivity>>>& parts;  // [record][equation of the group]
  const std::vector<NoiseBySignal>& noise;
  const std::vector<TestFunctionGrid>& grids;
  std::vector<Evaluator>& evaluators;

  // C(x), or why it cannot be had (a derivative that is not finite on the record: sqrt(y) where y = 0).
  std::variant<Eigen::SparseMatrix<double>, std::string> at(const Eigen::VectorXd& x, Eigen::Index rows) const {
    std::vector<Eigen::Triplet<double>> entries;
    Eigen::Index offset = 0;
    for (std::size_t r = 0; r < grids.size(); ++r) {
      const TestFunctionGrid& grid = grids[r];
      const std::size_t E = parts[r].size(), K = grid.centres.size(), m = grid.half_width, width = 2 * m + 1;
      // dG_k/ds on the window, per equation, order k and signal: sum_c x_c dg_ck/ds - dg_bk/ds.
      std::map<std::pair<int, std::string>, std::vector<std::vector<double>>> slopes;  // (k, s) -> per equation
      std::map<int, std::vector<double>> weights;                                      // phi^(k)'s quadrature weights
      std::vector<std::string> signals;
      for (std::size_t e = 0; e < E; ++e) {
        std::map<std::pair<int, std::string>, ir::Sum> combined;
        for (const Sensitivity& s : parts[r][e]) {
          const double factor = s.column ? x(static_cast<Eigen::Index>(*s.column)) : -1.0;
          if (factor == 0.0) continue;
          auto& sum = combined[{s.order, s.signal}];
          sum = ir::add(sum, ir::scale(s.derivative, Number::real(factor)));
        }
        for (const auto& [key, sum] : combined) {
          if (sum.terms.empty()) continue;
          auto values = evaluators[r].evaluate_in_window(sum, "the derivative of the rows by `" + key.second + "`");
          if (auto* d = std::get_if<Diagnostic>(&values)) return d->message;
          auto& per_equation = slopes[key];
          per_equation.resize(E);
          per_equation[e] = std::get<std::vector<double>>(std::move(values));
          if (!weights.count(key.first)) weights[key.first] = test_function_weights(grid, key.first, evaluators[r].record().step);
          if (std::find(signals.begin(), signals.end(), key.second) == signals.end()) signals.push_back(key.second);
        }
      }
      // L_js on subdomain j's support, per equation and signal; rows whose supports overlap
      // (centres at most 2m apart) are paired as j advances, so only a band of them is held.
      struct Row {
        std::size_t index = 0, centre = 0;
        std::vector<std::vector<double>> l;  // [equation * signals + signal][support sample]
      };
      std::deque<Row> band;
      const std::size_t S = signals.size();
      std::vector<double> variance(S);
      for (std::size_t s = 0; s < S; ++s) variance[s] = noise[r].at(signals[s]) * noise[r].at(signals[s]);
      for (std::size_t j = 0; j < K; ++j) {
        Row row{j, grid.centres[j], std::vector<std::vector<double>>(E * S, std::vector<double>(width, 0.0))};
        const std::size_t start = row.centre - m;
        for (const auto& [key, per_equation] : slopes) {
          const std::size_t s = static_cast<std::size_t>(std::find(signals.begin(), signals.end(), key.second) - signals.begin());
          const std::vector<double>& w = weights.at(key.first);
          for (std::size_t e = 0; e < per_equation.size(); ++e) {
            if (per_equation[e].empty()) continue;
            std::vector<double>& l = row.l[e * S + s];
            for (std::size_t i = 0; i < width; ++i) l[i] += w[i] * per_equation[e][start + i];
          }
        }
        while (!band.empty() && band.front().centre + 2 * m < row.centre) band.pop_front();
        band.push_back(std::move(row));
        const Row& now = band.back();
        // The lower triangle only (what the Cholesky factor reads), each pair of rows once.
        for (const Row& before : band) {
          const std::size_t shift = now.centre - before.centre;  // now's support starts `shift` samples later
          const std::size_t jb = before.index;
          for (std::size_t e1 = 0; e1 < E; ++e1)
            for (std::size_t e2 = jb == j ? e1 : 0; e2 < E; ++e2) {
              double c = 0;
              for (std::size_t s = 0; s < S; ++s) {
                const std::vector<double>& a = before.l[e1 * S + s];
                const std::vector<double>& b = now.l[e2 * S + s];
                c += variance[s] * running_dot(a.data() + shift, b.data(), width - shift);  // the covariance's innermost loop
              }
              if (c == 0.0) continue;
              const Eigen::Index p = offset + static_cast<Eigen::Index>(e1 * K + jb), q = offset + static_cast<Eigen::Index>(e2 * K + j);
              entries.emplace_back(std::max(p, q), std::min(p, q), c);
            }
        }
      }
      offset += static_cast<Eigen::Index>(E * K);
    }
    Eigen::SparseMatrix<double> C(rows, rows);  // its lower triangle
    C.setFromTriplets(entries.begin(), entries.end());
    return C;
  }
};

using Parts = std::vector<std::vector<std::vector<Sensitivity>>>;  // [record][equation of the group]

// Every record's and equation's sensitivities, or why there are none to write.
std::variant<Parts, std::string> all_sensitivities(const ir::Model& model, const DesignBuilder& design, const std::vector<std::size_t>& equations,
                                                   std::size_t records, const std::vector<NoiseBySignal>& noise) {
  Parts parts(records);
  bool noisy = false;
  for (std::size_t r = 0; r < records; ++r)
    for (std::size_t e : equations) {
      auto found = sensitivities(model, design, e, r, noise[r]);
      if (auto* why = std::get_if<std::string>(&found)) return std::move(*why);
      parts[r].push_back(std::get<std::vector<Sensitivity>>(std::move(found)));
      noisy = noisy || !parts[r].back().empty();
    }
  if (!noisy) return std::string("no signal the rows read is noisy (every noise level is 0)");
  return parts;
}

// b - A x, unweighted, for the residual files.
std::vector<double> residuals(const WeakDesign& weak, const LeastSquaresSummary& s) {
  Eigen::VectorXd x(static_cast<Eigen::Index>(s.parameters.size()));
  for (std::size_t c = 0; c < s.parameters.size(); ++c) x(static_cast<Eigen::Index>(c)) = s.parameters[c].value;
  const Eigen::VectorXd r = weak.b - weak.A * x;
  return {r.data(), r.data() + r.size()};
}

// Per row and column (and for the known side), sum_k integral(phi_j^(k) * 1/2 sum_s sigma_s^2
// d^2 g_k / ds^2): the rows' mean shift under the noise to second order, at unit noise scale. The
// second derivatives are those of the sensitivities' first ones (`parts`).
std::variant<std::pair<Eigen::MatrixXd, Eigen::VectorXd>, std::string> mean_shift(const Parts& parts, const DesignBuilder& design,
                                                                                  std::vector<Evaluator>& evaluators,
                                                                                  const std::vector<TestFunctionGrid>& grids,
                                                                                  const std::vector<NoiseBySignal>& noise) {
  Eigen::Index rows = 0;
  for (std::size_t r = 0; r < grids.size(); ++r) rows += static_cast<Eigen::Index>(grids[r].centres.size() * parts[r].size());
  std::pair<Eigen::MatrixXd, Eigen::VectorXd> out{Eigen::MatrixXd::Zero(rows, static_cast<Eigen::Index>(design.columns().size())),
                                                  Eigen::VectorXd::Zero(rows)};
  Eigen::Index offset = 0;
  for (std::size_t r = 0; r < grids.size(); ++r) {
    const TestFunctionGrid& grid = grids[r];
    const auto K = static_cast<Eigen::Index>(grid.centres.size());
    for (const auto& equation : parts[r]) {
      // sum_s sigma_s^2 / 2 d^2 g / ds^2 by (column, order of phi); the known side has no column.
      std::map<std::pair<std::optional<std::size_t>, int>, ir::Sum> curvature;
      for (const Sensitivity& s : equation) {
        auto twice = partial_derivative(s.derivative, s.signal, 0);
        if (!twice) return fmt::format("an int() or der() of `{}` in `{}`", s.signal, print(s.derivative));
        const double sigma = noise[r].at(s.signal);
        auto& sum = curvature[{s.column, s.order}];
        sum = ir::add(sum, ir::scale(*twice, Number::real(sigma * sigma / 2)));
      }
      for (const auto& [where, sum] : curvature) {
        if (sum.terms.empty()) continue;
        auto values = evaluators[r].evaluate_in_window(sum, "the curvature of the rows");
        if (auto* d = std::get_if<Diagnostic>(&values)) return d->message;
        const auto& v = std::get<std::vector<double>>(values);
        const std::vector<double> w = test_function_weights(grid, where.second, evaluators[r].record().step);
        for (Eigen::Index j = 0; j < K; ++j) {
          const double value = support_dot(w, v.data() + (grid.centres[static_cast<std::size_t>(j)] - grid.half_width));
          if (where.first) out.first(offset + j, static_cast<Eigen::Index>(*where.first)) += value;
          else out.second(offset + j) += value;
        }
      }
      offset += K;
    }
  }
  return out;
}

}  // namespace

std::variant<Eigen::SparseMatrix<double>, std::string> weak_row_covariance(
    const ir::Model& model, std::vector<Evaluator>& evaluators, const DesignBuilder& design, const std::vector<std::size_t>& equations,
    const WeakDesign& weak, const std::vector<NoiseBySignal>& noise, const Eigen::VectorXd& x) {
  auto gathered = all_sensitivities(model, design, equations, evaluators.size(), noise);
  if (auto* why = std::get_if<std::string>(&gathered)) return std::move(*why);
  const RowCovariance covariance{std::get<Parts>(gathered), noise, weak.grids, evaluators};
  auto made = covariance.at(x, weak.b.size());
  if (auto* why = std::get_if<std::string>(&made)) return std::move(*why);
  Eigen::SparseMatrix<double> full = std::get<Eigen::SparseMatrix<double>>(made).selfadjointView<Eigen::Lower>();
  return full;
}

std::pair<LeastSquaresSummary, WeakWeighting> weight_weak_rows(
    const ir::Model& model, std::vector<Evaluator>& evaluators, const DesignBuilder& design, const std::vector<std::size_t>& equations,
    const WeakDesign& weak, const std::vector<NoiseBySignal>& noise, const LeastSquaresSummary& unweighted,
    const std::vector<std::string>& columns, const LeastSquaresOptions& options) {
  WeakWeighting how;
  const auto keep = [&](std::string why) {
    how.note = "rows not weighted by their noise covariance: " + std::move(why);
    return std::pair{unweighted, how};
  };
  if (!unweighted.is_solution_usable()) return keep("the unweighted fit is not usable");
  auto gathered = all_sensitivities(model, design, equations, evaluators.size(), noise);
  if (auto* why = std::get_if<std::string>(&gathered)) return keep(*why);
  const auto& parts = std::get<Parts>(gathered);
  const RowCovariance covariance{parts, noise, weak.grids, evaluators};
  Eigen::VectorXd x(static_cast<Eigen::Index>(unweighted.parameters.size()));
  for (std::size_t c = 0; c < unweighted.parameters.size(); ++c) x(static_cast<Eigen::Index>(c)) = unweighted.parameters[c].value;
  LeastSquaresSummary solved = unweighted;
  // Generalised least squares on rows [A b], C recomputed at each new x until x settles; a reason
  // when it cannot go on.
  const auto iterate = [&](const Eigen::MatrixXd& A0, const Eigen::VectorXd& b0, int most) -> std::optional<std::string> {
    for (int solve = 1; solve <= most; ++solve) {
      auto made = covariance.at(x, b0.size());
      if (auto* why = std::get_if<std::string>(&made)) return *why;
      Eigen::SparseMatrix<double>& C = std::get<Eigen::SparseMatrix<double>>(made);
      // A row no noise reaches would be exact; a ridge of 1e-12 of the largest variance keeps C
      // positive definite without changing any row that noise does reach.
      double largest = 0;
      for (Eigen::Index i = 0; i < C.rows(); ++i) largest = std::max(largest, C.coeff(i, i));
      if (!(largest > 0) || !std::isfinite(largest)) return std::string("the rows' covariance is zero or not finite");
      for (Eigen::Index i = 0; i < C.rows(); ++i) C.coeffRef(i, i) += 1e-12 * largest;
      Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> factor(C);
      if (factor.info() != Eigen::Success) return std::string("the rows' covariance is not positive definite");
      const Eigen::MatrixXd A = factor.matrixL().solve(Eigen::MatrixXd(factor.permutationP() * A0));
      const Eigen::VectorXd b = factor.matrixL().solve(Eigen::VectorXd(factor.permutationP() * b0));
      LeastSquaresSummary next = solve_least_squares(A, b, columns, nullptr, options);
      if (!next.is_solution_usable()) return "a weighted solve was not usable (" + next.message + ")";
      Eigen::VectorXd y(x.size());
      for (std::size_t c = 0; c < next.parameters.size(); ++c) y(static_cast<Eigen::Index>(c)) = next.parameters[c].value;
      const double change = (y - x).lpNorm<Eigen::Infinity>() / std::max(y.lpNorm<Eigen::Infinity>(), 1e-300);
      x = y;
      solved = std::move(next);
      ++how.iterations;
      how.residual_variance = solved.residual_sd * solved.residual_sd;
      if (change <= kSettled || (solve == most && most < kMostSolves)) return std::nullopt;  // settled, or as many solves as asked
    }
    return fmt::format("the iteration did not settle in {} solves", kMostSolves);
  };
  const auto noise_dominates = [&] { return how.residual_variance <= kMostResidualVariance; };
  const auto dominated = [&] {
    return keep(fmt::format("weighted, their residuals are {:.3g} times what the signals' noise levels explain, so something else "
                            "dominates them (a term the model lacks, or the discretisation of a record with little noise)",
                            std::sqrt(how.residual_variance)));
  };
  // The operations' mean shift under noise, E g(s + e) - g(s) = sigma^2 g''(s) / 2 (exact for a
  // cubic: E (y + e)^3 = y^3 + 3 sigma^2 y), is taken out of the rows with the noise variances the
  // weighted residuals calibrate (their variance times each signal's estimated one). Where there is
  // one, a first weighted solve calibrates and the corrected rows are iterated until they settle.
  auto shift = mean_shift(parts, design, evaluators, weak.grids, noise);
  if (auto* why = std::get_if<std::string>(&shift)) return keep(*why);
  const auto& [dA, db] = std::get<std::pair<Eigen::MatrixXd, Eigen::VectorXd>>(shift);
  const bool shifted = dA.any() || db.any();  // any(): some entry is not zero
  if (auto why = iterate(weak.A, weak.b, shifted ? 1 : kMostSolves)) return keep(*why);
  if (!noise_dominates()) return dominated();
  WeakDesign fitted;
  fitted.A = weak.A - how.residual_variance * dA;
  fitted.b = weak.b - how.residual_variance * db;
  if (shifted) {
    if (auto why = iterate(fitted.A, fitted.b, kMostSolves)) return keep(*why);
    if (!noise_dominates()) return dominated();
  }
  how.applied = true;
  solved.residuals = residuals(fitted, solved);
  how.note = fmt::format(
      "rows weighted by the covariance their noise gives them (generalised least squares, iterated: WENDy, {} solve{}){}; "
      "residual variance of the weighted rows {:.3g} (about 1 when the noise explains the residuals); G(a) and the statistics "
      "below are the weighted rows'",
      how.iterations, how.iterations == 1 ? "" : "s",
      shifted ? ", the operations' mean shift under the noise, sigma^2 g''/2, taken out" : "", how.residual_variance);
  return std::pair{std::move(solved), how};
}

}  // namespace sidc
