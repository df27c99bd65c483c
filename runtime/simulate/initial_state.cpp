// Levenberg-Marquardt over the initial state (see initial_state.hpp).
#include "runtime/simulate/initial_state.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <span>

#include "runtime/operators/noise_level.hpp"

namespace sidc {
namespace {

constexpr int kMaxIterations = 30;
constexpr int kMaxDampingTries = 12;  // lambda grows tenfold per rejected trial step

// The segment's least-squares problem: the state as a vector, its residuals by a free run.
class StartProblem {
 public:
  StartProblem(const ir::Model& model, const ExplicitForm& form, const SimulateOptions& whole, const std::vector<Column>& recorded,
               std::size_t segment)
      : model_(model), form_(form), options_(whole.first_samples(segment)), recorded_(recorded), segment_(segment) {
    const double duration = options_.time.back() - options_.time.front();
    for (std::size_t j = 0; j < form.outputs.size(); ++j) {
      // Finite and non-zero in any unit, so the residuals below are of order 1.
      const double sd = standard_deviation(std::span<const double>(recorded[j].data(), segment));
      scale_.push_back(sd > 0 && std::isfinite(sd) ? sd : 1.0);
      // A typical size of y^(m) for the finite-difference steps: the spread over the segment's duration^m.
      for (int m = 0; m < form.outputs[j].order; ++m) {
        typical_.push_back(scale_.back() / std::pow(duration > 0 ? duration : 1.0, m));
      }
    }
  }

  std::size_t size() const { return form_.state_size(); }
  std::size_t rows() const { return segment_ * form_.outputs.size(); }
  double typical(std::size_t k) const { return typical_[k]; }
  const std::vector<double>& scales() const { return scale_; }

  Eigen::VectorXd vector_of(const std::map<std::string, std::vector<double>>& initial) const {
    const std::vector<double> x = state_vector(form_, initial);
    return Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size()));
  }

  std::map<std::string, std::vector<double>> map_of(const Eigen::VectorXd& x) const {
    return state_map(form_, std::span<const double>(x.data(), static_cast<std::size_t>(x.size())));
  }

  // (recorded - simulated) / s_j over the segment; false when the run fails or is not finite.
  bool residuals(const Eigen::VectorXd& x, Eigen::VectorXd& r) {
    options_.initial = map_of(x);
    auto run = simulate(model_, form_, options_);
    if (!std::holds_alternative<SimulationSummary>(run)) return false;
    const auto& s = std::get<SimulationSummary>(run);
    if (!s.completed()) return false;
    r.resize(static_cast<Eigen::Index>(rows()));
    for (std::size_t j = 0; j < form_.outputs.size(); ++j)
      for (std::size_t i = 0; i < segment_; ++i) {
        const double v = (recorded_[j][i] - s.outputs[j][i]) / scale_[j];
        if (!std::isfinite(v)) return false;
        r(static_cast<Eigen::Index>(j * segment_ + i)) = v;
      }
    return true;
  }

 private:
  const ir::Model& model_;
  const ExplicitForm& form_;
  SimulateOptions options_;
  const std::vector<Column>& recorded_;
  std::size_t segment_;
  std::vector<double> scale_, typical_;
};

}  // namespace

InitialStateEstimate estimate_initial_state(const ir::Model& normalized, const ExplicitForm& form, const SimulateOptions& options,
                                            const std::vector<Column>& recorded, std::size_t segment) {
  InitialStateEstimate out;
  out.initial = options.initial;
  segment = std::clamp<std::size_t>(segment, 2, options.time.size());
  out.segment = segment;
  if (options.time.size() < 2) return out;
  StartProblem problem(normalized, form, options, recorded, segment);
  Eigen::VectorXd x = problem.vector_of(options.initial), r, trial_r, shifted_r;
  out.initial = problem.map_of(x);
  if (!problem.residuals(x, r)) {  // the guess itself cannot be run: the full run will say why
    out.cost_before = out.cost_after = INFINITY;
    return out;
  }
  double cost = r.squaredNorm();
  out.cost_before = cost;
  const auto n = static_cast<Eigen::Index>(problem.size());
  Eigen::MatrixXd J(r.size(), n);
  double lambda = 1e-3;
  bool jacobian_at_hand = false;
  for (int iteration = 0; iteration < kMaxIterations && cost > 0; ++iteration) {
    // Forward differences: RK4 on a fixed grid is a smooth function of the start (linear for a
    // linear model), so a relative step of 1e-7 loses only the digits that step costs.
    bool sensitivities = true;
    for (Eigen::Index k = 0; k < n && sensitivities; ++k) {
      double h = 1e-7 * (std::abs(x(k)) + problem.typical(static_cast<std::size_t>(k)));
      Eigen::VectorXd shifted = x;
      shifted(k) += h;
      if (!problem.residuals(shifted, shifted_r)) {  // the other side, when that direction diverges
        h = -h;
        shifted(k) = x(k) + h;
        sensitivities = problem.residuals(shifted, shifted_r);
      }
      if (sensitivities) J.col(k) = (shifted_r - r) / h;
    }
    if (!sensitivities) break;
    const Eigen::MatrixXd normal = J.transpose() * J;
    jacobian_at_hand = true;
    const Eigen::VectorXd gradient = J.transpose() * r;
    const double largest = normal.diagonal().maxCoeff();
    if (!(largest > 0)) break;  // the segment does not depend on the start
    bool accepted = false;
    double trial_cost = cost;
    for (int attempt = 0; attempt < kMaxDampingTries && !accepted; ++attempt) {
      Eigen::MatrixXd damped = normal;
      for (Eigen::Index k = 0; k < n; ++k) damped(k, k) += lambda * std::max(normal(k, k), 1e-12 * largest);
      const Eigen::VectorXd step = damped.ldlt().solve(-gradient);
      const Eigen::VectorXd trial = x + step;
      if (step.allFinite() && problem.residuals(trial, trial_r) && (trial_cost = trial_r.squaredNorm()) < cost) {
        accepted = true;
        x = trial;
        r = trial_r;
        lambda = std::max(lambda / 10, 1e-12);
      } else {
        lambda *= 10;
      }
    }
    if (!accepted) break;
    ++out.iterations;
    const double decrease = cost - trial_cost;
    cost = trial_cost;
    if (decrease <= 1e-10 * cost) break;  // converged: a further step would change nothing visible
  }
  out.initial = problem.map_of(x);
  out.cost_after = cost;
  // The uncertainty's axes from the last Jacobian (taken at the iterate before the last step, which
  // the convergence test makes a negligible difference).
  const auto rows = static_cast<Eigen::Index>(problem.rows());
  if (jacobian_at_hand && rows > n) {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeThinV);
    out.scales = problem.scales();
    for (Eigen::Index k = 0; k < n; ++k) {
      const double s = svd.singularValues()(k);
      if (!(s > 0)) {
        out.uncertainty_axes.clear();
        break;
      }
      const Eigen::VectorXd axis = svd.matrixV().col(k) / s;
      if (!axis.allFinite()) {
        out.uncertainty_axes.clear();
        break;
      }
      out.uncertainty_axes.emplace_back(axis.data(), axis.data() + axis.size());
    }
  }
  return out;
}

}  // namespace sidc
