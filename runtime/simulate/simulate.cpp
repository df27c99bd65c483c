#include "runtime/simulate/simulate.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <boost/numeric/odeint.hpp>
#include <cmath>
#include <limits>
#include <fmt/format.h>
#include <stdexcept>

#include "ir/differentiate.hpp"
#include "ir/fix_parameters.hpp"
#include "diagnostics/data_catalogue.hpp"
#include "diagnostics/model_catalogue.hpp"
#include "runtime/operators/operator_choice.hpp"
#include "runtime/operators/point_evaluator.hpp"
#include "runtime/operators/weighted_point_sum.hpp"
#include "runtime/operators/savitzky_golay.hpp"
#include "runtime/not_a_number.hpp"

namespace sidc {
namespace {

std::string prime(const std::string& name, int order) { return name + std::string(static_cast<std::size_t>(order), '\''); }

// A ParametricSum with the parameter values substituted, sum_k a_k * term_k(point), is a
// WeightedPointSum; each part's value is kept for the sensitivity equations, where d/d a_k of the
// sum is part k itself.
using Weighted = WeightedPointSum;

// The 4-point cubic through the samples around t (Lagrange form); the stencil shifts inward at
// the ends of the grid. Exact for cubics, so the interpolation error is O(h^4), RK4's order.
// `hint`: the sample interval of the last call, tried with the next one before a binary search
// (steppers move forward), and set to the interval found.
double interpolate_cubic(std::span<const double> time, std::span<const double> v, double t, std::size_t& hint) {
  const std::size_t n = time.size();
  if (n == 1) return v[0];
  auto inside = [&](std::size_t k) { return k + 1 < n && time[k] <= t && t < time[k + 1]; };
  std::size_t k = hint;
  if (!inside(k)) {
    if (inside(k + 1)) {
      ++k;
    } else {
      auto upper = std::upper_bound(time.begin(), time.end(), t);
      k = upper == time.begin() ? 0 : static_cast<std::size_t>(upper - time.begin()) - 1;  // time[k] <= t
    }
  }
  hint = k;
  if (k >= n - 1) k = n - 2;
  if (n < 4) {
    const double a = (t - time[k]) / (time[k + 1] - time[k]);
    return (1 - a) * v[k] + a * v[k + 1];
  }
  std::size_t first = k == 0 ? 0 : k - 1;
  if (first + 3 >= n) first = n - 4;
  double total = 0;
  for (std::size_t i = first; i < first + 4; ++i) {
    double w = 1;
    for (std::size_t j = first; j < first + 4; ++j)
      if (j != i) w *= (t - time[j]) / (time[i] - time[j]);
    total += w * v[i];
  }
  return total;
}

class System {
 public:
  // Returns a Diagnostic when something of the model has no value at a point. `form` has its
  // nonlinear parameters substituted; `full` (with sensitivities) still holds them as factors, for
  // the partial derivatives by them.
  std::optional<Diagnostic> build(const ir::Model& model, const ExplicitForm& form, const SimulateOptions& o, const ExplicitForm* full = nullptr) {
    form_ = &form;
    compile_options_.initial_value = o.initial_value;
    compile_options_.switching_functions = form.switching_functions;
    options_ = &o;
    sensitivities_ = o.sensitivities;
    // A part whose parameter is 0 adds nothing to the equations, but its sensitivity is the part itself.
    auto weighted = [&](const ParametricSum& p, Weighted& out) -> std::optional<Diagnostic> {
      auto add = [&](double w, int parameter, const ir::Sum& s) -> std::optional<Diagnostic> {
        if (s.empty() || (w == 0 && !sensitivities_)) return std::nullopt;
        return out.add(w, parameter, s, layout_, compile_options_);
      };
      if (auto d = add(1.0, -1, p.constant)) return d;
      for (const auto& t : p.terms)
        if (auto d = add(o.parameters[static_cast<std::size_t>(t.parameter)], t.parameter, t.operation)) return d;
      return std::nullopt;
    };
    // d/dx_m of a ParametricSum for each state component x_m: the Jacobian the variational
    // equations need, derived symbolically (ir/differentiate.hpp), weighted like the sum itself.
    // The parameter values are fixed for the run, so each partial is one Sum, sum_k a_k d(term_k)/dx_m,
    // compiled once: one evaluation per state component instead of one per term.
    auto partials = [&](const ParametricSum& p, std::vector<Weighted>& out) -> std::optional<Diagnostic> {
      out.assign(form.state_size(), {});
      std::size_t m = 0;
      for (const auto& output : form.outputs)
        for (int order = 0; order < output.order; ++order, ++m) {
          ir::Sum total;
          auto add = [&](double w, const ir::Sum& s, Span span) -> std::optional<Diagnostic> {
            if (s.empty() || w == 0) return std::nullopt;
            auto d = partial_derivative(s, output.name, order);
            if (!d) return diag::simulate_estimated_derivative(span, prime(output.name, order));
            total = ir::add(total, w == 1 ? *d : ir::scale(*d, Number::real(w)));
            return std::nullopt;
          };
          if (auto d = add(1.0, p.constant, output.span)) return d;
          for (const auto& t : p.terms)
            if (auto d = add(o.parameters[static_cast<std::size_t>(t.parameter)], t.operation, output.span)) return d;
          if (total.empty()) continue;
          if (auto e = out[m].add(1.0, -1, total, layout_, compile_options_)) return e;
        }
      return std::nullopt;
    };
    const std::size_t k = form.outputs.size();
    coefficient_.assign(k, std::vector<Weighted>(k));
    rest_.assign(k, {});
    for (std::size_t i = 0; i < k; ++i) {
      for (std::size_t j = 0; j < k; ++j)
        if (auto d = weighted(form.coefficient[i][j], coefficient_[i][j])) return d;
      if (auto d = weighted(form.rest[i], rest_[i])) return d;
    }
    // Each equation holds its own output's highest derivative only (one output, or x' = ..., y' = ...,
    // z' = ...: the usual case): the solve is then a division per equation, with the LU's bits.
    diagonal_ = true;
    for (std::size_t i = 0; i < k; ++i)
      for (std::size_t j = 0; j < k; ++j) diagonal_ = diagonal_ && (i == j || coefficient_[i][j].empty());
    if (sensitivities_) {
      parameters_ = o.parameters.size();
      coefficient_partial_.assign(k, std::vector<std::vector<Weighted>>(k));
      rest_partial_.assign(k, {});
      for (std::size_t i = 0; i < k; ++i) {
        for (std::size_t j = 0; j < k; ++j)
          if (auto d = partials(form.coefficient[i][j], coefficient_partial_[i][j])) return d;
        if (auto d = partials(form.rest[i], rest_partial_[i])) return d;
      }
    }
    if (sensitivities_ && full)
      if (auto d = nonlinear_partials(model, *full, o)) return d;
    // A threshold that is a nonlinear parameter (`[y > y0]`): the switch time moves with it too.
    switching_nonlinear_.assign(form.switching_functions.size(), {});
    if (sensitivities_ && full)
      for (std::size_t i = 0; i < full->switching_functions.size(); ++i)
        for (std::size_t q = 0; q < model.parameters.size(); ++q) {
          if (!model.parameters[q].nonlinear) continue;
          auto d = partial_derivative_by_parameter(full->switching_functions[i], static_cast<int>(q));
          if (!d) return diag::simulate_estimated_derivative(model.parameters[q].span, model.parameters[q].name);
          if (d->empty()) continue;
          auto c = compile_point_sum(substitute_parameters(*d, o.parameters), layout_, compile_options_);
          if (auto* e = std::get_if<Diagnostic>(&c)) return *e;
          switching_nonlinear_[i].emplace_back(q, std::get<PointSum>(std::move(c)));
        }
    for (const auto& g : form.switching_functions) {
      auto c = compile_point_sum(g, layout_, compile_options_);
      if (auto* d = std::get_if<Diagnostic>(&c)) return *d;
      switching_.push_back(std::get<PointSum>(std::move(c)));
      if (!sensitivities_) continue;
      // d g / d x_m, for the jump of the sensitivities where g changes sign.
      switching_partial_.emplace_back();
      for (const auto& output : form.outputs)
        for (int order = 0; order < output.order; ++order) {
          auto d = partial_derivative(g, output.name, order);
          if (!d) return diag::simulate_estimated_derivative(output.span, prime(output.name, order));
          auto pc = compile_point_sum(*d, layout_, compile_options_);
          if (auto* e = std::get_if<Diagnostic>(&pc)) return *e;
          switching_partial_.back().push_back(std::get<PointSum>(std::move(pc)));
        }
    }
    // Where each slot's value comes from: the state, an input definition or an input column.
    std::size_t offset = 0;
    for (const auto& out : form.outputs) {
      state_offset_.push_back(offset);
      offset += static_cast<std::size_t>(out.order);
    }
    for (std::size_t s = 0; s < layout_.size(); ++s) {
      const auto& [name, order] = layout_.slots()[s];
      Source source;
      source.slot = s;
      const auto out = std::find_if(form.outputs.begin(), form.outputs.end(), [&slot_name = name](const auto& x) { return x.name == slot_name; });
      if (out != form.outputs.end()) {
        source.kind = Source::Kind::state;
        source.index = state_offset_[static_cast<std::size_t>(out - form.outputs.begin())] + static_cast<std::size_t>(order);
      } else if (const ir::Signal* signal = model.signal(name); signal && signal->definition) {
        auto derivative = order == 0 ? std::optional<ir::Sum>(*signal->definition) : differentiate(*signal->definition, order);
        if (!derivative) return diag::simulate_estimated_derivative(signal->span, prime(name, order));
        PointLayout none;
        auto c = compile_point_sum(*derivative, none, compile_options_);
        if (auto* d = std::get_if<Diagnostic>(&c)) return *d;
        source.kind = Source::Kind::definition;
        source.definition = std::get<PointSum>(std::move(c));
      } else {
        auto column = o.inputs.find(name);
        if (column == o.inputs.end())
          return diag::signal_not_in_record(signal ? signal->span : Span{}, name, "the simulation's inputs");
        source.kind = Source::Kind::column;
        source.hold = signal ? signal->hold : ir::Signal::Hold::smooth;
        if (order > 0 && source.hold != ir::Signal::Hold::smooth)  // a step or a kink has no derivative to estimate
          return diag::simulate_derivative_of_held_input(signal->hold_span.known() ? signal->hold_span : signal->span, name,
                                                         to_string(source.hold), prime(name, order));
        if (order == 0) {
          source.column = &column->second;  // the options outlive the run
        } else {  // a recorded input's derivative: the moving arc on the record, then interpolated
          DerivativeOptions d;
          d.edges = DerivativeOptions::Edges::shorten;
          const double step = o.time.size() > 1 ? (o.time.back() - o.time.front()) / static_cast<double>(o.time.size() - 1) : 1.0;
          auto estimate = estimate_derivative(column->second, step, order, d);
          if (auto* e = std::get_if<Diagnostic>(&estimate)) return *e;
          source.owned = std::get<std::vector<double>>(std::move(estimate));
        }
      }
      sources_.push_back(std::move(source));
    }
    slots_.assign(layout_.size(), 0.0);
    return std::nullopt;
  }

  std::size_t state_size() const { return form_->state_size(); }
  // The integrated vector: the state, then (with sensitivities) d state / d q column by column for
  // q = the parameters, then the initial state's components.
  std::size_t sensitivity_columns() const { return sensitivities_ ? parameters_ + state_size() : 0; }
  std::size_t vector_size() const { return state_size() * (1 + sensitivity_columns()); }

  // Whether an input holds or runs straight between samples: then no step may cross a sample
  // instant, and the stepping loops say which sample interval they step in.
  bool has_piecewise_inputs() const {
    return std::any_of(sources_.begin(), sources_.end(),
                       [](const Source& s) { return s.kind == Source::Kind::column && s.hold != ir::Signal::Hold::smooth; });
  }
  // Held and linear inputs take their value from [time[k], time[k+1]], even at its right end: the
  // last stage of a step that ends at a sample sees the left limit, not the next sample's value.
  void set_interval(std::size_t k) { interval_ = options_->time.size() < 2 ? 0 : std::min(k, options_->time.size() - 2); }

  void fill(double t, const double* state) {
    for (const auto& s : sources_) {
      double v = 0;
      switch (s.kind) {
        case Source::Kind::state: v = state[s.index]; break;
        case Source::Kind::definition: v = s.definition.evaluate({std::span<const double>(), t, options_->t0_for_tau, {}}); break;
        case Source::Kind::column: v = recorded(s, t); break;
      }
      slots_[s.slot] = v;
    }
  }

  PointInstant instant(double t) const {
    return {slots_, t, options_->t0_for_tau, frozen_ ? std::span<const signed char>(modes_) : std::span<const signed char>()};
  }

  // The modes of the step starting at (t, state): each switching function's sign there (kLiveMode
  // where it is 0: the step itself decides), used by every stage until the next freeze or thaw.
  void freeze(double t, const double* state) {
    switching_values(t, state, frozen_values_);
    freeze(frozen_values_);
  }
  // The same from the switching functions' values there, when the caller has them.
  void freeze(const std::vector<double>& g) {
    modes_.resize(g.size());
    for (std::size_t i = 0; i < g.size(); ++i) modes_[i] = g[i] > 0 ? 1 : g[i] < 0 ? -1 : kLiveMode;
    frozen_ = true;
  }
  void thaw() { frozen_ = false; }

  // dstate/dt; false (and `trouble` set) when the highest derivatives cannot be solved for.
  bool derivative(double t, const double* state, double* out) {
    ++evaluations;
    fill(t, state);
    const PointInstant at = instant(t);
    const std::size_t k = form_->outputs.size();
    for (std::size_t j = 0; j < k; ++j) {  // y^(m)' = y^(m+1) for m < n-1
      const std::size_t base = state_offset_[j];
      for (int m = 0; m + 1 < form_->outputs[j].order; ++m) out[base + static_cast<std::size_t>(m)] = state[base + static_cast<std::size_t>(m) + 1];
    }
    double det = 0;
    if (diagonal_) {
      // What PartialPivLU gives for a diagonal matrix (one output, or equations that each hold only
      // their own output's highest derivative), without its allocations: no row swaps (each
      // column's largest entry is on the diagonal, the others being 0), a unit L, and each highest
      // derivative -r_i / a_ii (the triangular solves subtract exact zeros).
      if (sensitivities_) {
        a_.setZero(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k));
        z_.resize(static_cast<Eigen::Index>(k));
      }
      det = 1;
      for (std::size_t i = 0; i < k; ++i) {
        const double a = coefficient_[i][i].evaluate(at), r = rest_[i].evaluate(at);
        det *= a;
        out[state_offset_[i] + static_cast<std::size_t>(form_->outputs[i].order) - 1] = -r / a;
        if (sensitivities_) {
          const auto ii = static_cast<Eigen::Index>(i);
          a_(ii, ii) = a;
          z_(ii) = -r / a;
        }
      }
    } else {
      a_.resize(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k));
      Eigen::VectorXd r(k);
      for (std::size_t i = 0; i < k; ++i) {
        for (std::size_t j = 0; j < k; ++j) a_(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = coefficient_[i][j].evaluate(at);
        r(static_cast<Eigen::Index>(i)) = rest_[i].evaluate(at);
      }
      Eigen::PartialPivLU<Eigen::MatrixXd> lu(a_);
      det = lu.determinant();
      z_ = lu.solve(-r);
      for (std::size_t j = 0; j < k; ++j)
        out[state_offset_[j] + static_cast<std::size_t>(form_->outputs[j].order) - 1] = z_(static_cast<Eigen::Index>(j));
    }
    if (sensitivities_ && std::isfinite(det) && det != 0) sensitivity_derivative(at, state, out);
    // eq. 4-1.1 divided by m: a coefficient that vanishes or changes sign on the way makes the
    // highest derivative infinite or the equation a different one; stop there.
    if (!initial_det_) initial_det_ = det;
    last_det_ = det;
    if (!std::isfinite(det) || std::abs(det) <= 1e-12 * std::abs(*initial_det_) || (det > 0) != (*initial_det_ > 0)) {
      if (!trouble) singular_at(t);
      return false;
    }
    return true;
  }

  // The adaptive stepper stalls before the coefficient is exactly 0: a coefficient below 1e-6 of
  // its start where it stalls is the reason.
  bool nearly_singular() const { return initial_det_ && std::abs(last_det_) < 1e-6 * std::abs(*initial_det_); }

  void singular_at(double t) {
    trouble_time = t;
    const std::size_t k = form_->outputs.size();
    const std::string what = k == 1 ? fmt::format("the coefficient of `{}`", prime(form_->outputs[0].name, form_->outputs[0].order))
                                    : std::string("the determinant of the coefficients of the highest derivatives");
    trouble = fmt::format("{} is {:.6g} at t = {:.6g} (it was {:.6g} at the start): it vanishes or changes sign on the trajectory, "
                          "so the equation cannot be solved for the highest derivative there",
                          what, last_det_, t, initial_det_.value_or(0.0));
  }

  // The switching functions' values at (t, state).
  void switching_values(double t, const double* state, std::vector<double>& g) {
    g.resize(switching_.size());
    if (switching_.empty()) return;
    fill(t, state);
    const PointInstant at{slots_, t, options_->t0_for_tau, {}};  // always live: they decide the modes
    for (std::size_t i = 0; i < switching_.size(); ++i) g[i] = switching_[i].evaluate(at);
  }
  bool has_switches() const { return !switching_.empty(); }

  // The sensitivities' jump where switching function g changes sign between (before, x_before)
  // and (after, x_after): the state is continuous but the right-hand side jumps from f- to f+,
  // and the switch time moves with every parameter, d tau/dq = -(g_x S + g_q)/(g_x f- + g_t), so
  // S+ = S- + (f+ - f-) (g_x S- + g_q) / (g_x f- + g_t) (Hiskens and Pai, IEEE TCAS-I 47(2), 2000,
  // eq. 12); g_q is 0 but for a nonlinear parameter in g (`[y > y0]`). g_t, where g reads t or an
  // input, by a central difference in time at fixed state.
  void jump_sensitivities(double before, std::vector<double>& x_before, double after, std::vector<double>& x_after) {
    if (!sensitivities_ || switching_.empty()) return;
    const std::size_t n = state_size(), columns = sensitivity_columns();
    std::vector<double> g_before, g_after, f_before(x_before.size()), f_after(x_after.size());
    switching_values(before, x_before.data(), g_before);
    switching_values(after, x_after.data(), g_after);
    // f- in the step's frozen modes, f+ in the modes after the switch.
    if (!derivative(before, x_before.data(), f_before.data())) return;
    freeze(after, x_after.data());
    if (!derivative(after, x_after.data(), f_after.data())) return;
    thaw();
    for (std::size_t i = 0; i < switching_.size(); ++i) {
      if (!(g_before[i] * g_after[i] < 0)) continue;
      fill(before, x_before.data());
      const PointInstant at{slots_, before, options_->t0_for_tau, {}};
      std::vector<double> gx(n);
      double speed = 0;  // dg/dt along the trajectory before the switch
      for (std::size_t m = 0; m < n; ++m) {
        gx[m] = switching_partial_[i][m].evaluate(at);
        speed += gx[m] * f_before[m];
      }
      const double delta = 1e-6 * std::max(1.0, std::abs(before));
      fill(before + delta, x_before.data());
      const double up = switching_[i].evaluate({slots_, before + delta, options_->t0_for_tau, {}});
      fill(before - delta, x_before.data());
      const double down = switching_[i].evaluate({slots_, before - delta, options_->t0_for_tau, {}});
      speed += (up - down) / (2 * delta);
      if (!(std::abs(speed) > 0) || !std::isfinite(speed)) continue;  // grazing: no transversal crossing to move
      std::vector<double> gq(columns, 0.0);
      fill(before, x_before.data());
      for (auto& [q, partial] : switching_nonlinear_[i]) gq[q] = partial.evaluate({slots_, before, options_->t0_for_tau, {}});
      for (std::size_t q = 0; q < columns; ++q) {
        double* column = x_after.data() + n + q * n;
        double moved = gq[q];
        for (std::size_t m = 0; m < n; ++m) moved += gx[m] * column[m];
        moved /= speed;
        for (std::size_t m = 0; m < n; ++m) column[m] += (f_after[m] - f_before[m]) * moved;
      }
    }
  }

  // d/dL of each side for each nonlinear parameter L (`sin(L*theta)` -> `cos(L*theta)*theta`, times
  // the linear parameter it stands beside), derived from the unsubstituted form and evaluated at
  // the run's values: the sensitivity equations' inhomogeneous column for L, as a side's part is
  // for a linear parameter.
  std::optional<Diagnostic> nonlinear_partials(const ir::Model& model, const ExplicitForm& full, const SimulateOptions& o) {
    const std::size_t k = full.outputs.size();
    rest_nonlinear_.assign(k, {});
    coefficient_nonlinear_.assign(k, std::vector<Weighted>(k));
    const auto by = [&](const ParametricSum& p, int q, Weighted& out) -> std::optional<Diagnostic> {
      ir::Sum total;
      auto add = [&](double w, const ir::Sum& s) -> bool {
        if (s.empty() || w == 0) return true;
        auto d = partial_derivative_by_parameter(s, q);
        if (!d) return false;
        total = ir::add(total, w == 1 ? *d : ir::scale(*d, Number::real(w)));
        return true;
      };
      bool ok = add(1.0, p.constant);
      for (const auto& t : p.terms) ok = ok && add(o.parameters[static_cast<std::size_t>(t.parameter)], t.operation);
      const auto& parameter = model.parameters[static_cast<std::size_t>(q)];
      if (!ok) return diag::simulate_estimated_derivative(parameter.span, parameter.name);
      if (total.empty()) return std::nullopt;
      return out.add(1.0, q, substitute_parameters(total, o.parameters), layout_, compile_options_);
    };
    for (std::size_t q = 0; q < model.parameters.size(); ++q) {
      if (!model.parameters[q].nonlinear) continue;
      for (std::size_t i = 0; i < k; ++i) {
        for (std::size_t j = 0; j < k; ++j)
          if (auto d = by(full.coefficient[i][j], static_cast<int>(q), coefficient_nonlinear_[i][j])) return d;
        if (auto d = by(full.rest[i], static_cast<int>(q), rest_nonlinear_[i])) return d;
      }
    }
    return std::nullopt;
  }

  std::vector<std::size_t> state_offset_;
  std::size_t evaluations = 0;
  std::optional<std::string> trouble;
  double trouble_time = 0;

 private:
  // The variational equations (the state's sensitivities S = d x / d q, column by column after the
  // state): dS/dt = J_x S + [J_p 0]. For the chain rows (y^(m))' = y^(m+1) this is S's next row;
  // for the highest derivatives z, from A z + r = 0: A dz/dq = -(d(A z + r)/dx S + d(A z + r)/dp).
  // Integrated by the same RK4 steps as the state, S is the exact derivative of the discrete run.
  void sensitivity_derivative(const PointInstant& at, const double* state, double* out) {
    // Plain loops over small row-major arrays: the sizes (k outputs, n states, Q columns) are a
    // handful each, where dynamic Eigen matrices cost more in bookkeeping than in arithmetic.
    const std::size_t k = form_->outputs.size(), n = state_size(), q_count = sensitivity_columns();
    // G = d(A z + r)/dx (k x n); C = G S + [H 0], H = d(A z + r)/dp (k x P).
    g_.assign(k * n, 0.0);
    c_.assign(k * q_count, 0.0);
    for (std::size_t i = 0; i < k; ++i) {
      double* g = &g_[i * n];
      double* c = &c_[i * q_count];
      auto add_parameters = [&](const Weighted& w, double factor) {
        for (std::size_t p = 0; p < w.parts(); ++p)
          if (w.parameter(p) >= 0) c[w.parameter(p)] += factor * w.part_value(p);
      };
      for (std::size_t m = 0; m < n; ++m)
        if (!rest_partial_[i][m].empty()) g[m] += rest_partial_[i][m].evaluate(at);
      add_parameters(rest_[i], 1.0);
      if (!rest_nonlinear_.empty() && !rest_nonlinear_[i].empty()) {
        rest_nonlinear_[i].evaluate(at);
        add_parameters(rest_nonlinear_[i], 1.0);
      }
      for (std::size_t j = 0; j < k; ++j) {
        const double zj = z_(static_cast<Eigen::Index>(j));
        for (std::size_t m = 0; m < n; ++m)
          if (!coefficient_partial_[i][j][m].empty()) g[m] += zj * coefficient_partial_[i][j][m].evaluate(at);
        add_parameters(coefficient_[i][j], zj);
        if (!coefficient_nonlinear_.empty() && !coefficient_nonlinear_[i][j].empty()) {
          coefficient_nonlinear_[i][j].evaluate(at);
          add_parameters(coefficient_nonlinear_[i][j], zj);
        }
      }
      const double* sensitivity = state + n;  // column q of S starts at q * n
      for (std::size_t q = 0; q < q_count; ++q)
        for (std::size_t m = 0; m < n; ++m) c[q] += g[m] * sensitivity[q * n + m];
    }
    if (k == 1) {
      const double scale = -1 / a_(0, 0);
      for (double& v : c_) v *= scale;
    } else {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> c(c_.data(), static_cast<Eigen::Index>(k),
                                                                                         static_cast<Eigen::Index>(q_count));
      c = a_.partialPivLu().solve(-c).eval();  // now dz/dq
    }
    for (std::size_t q = 0; q < q_count; ++q) {
      const double* s = state + n + q * n;
      double* ds = out + n + q * n;
      for (std::size_t j = 0; j < k; ++j) {
        const std::size_t base = state_offset_[j];
        const auto order = static_cast<std::size_t>(form_->outputs[j].order);
        for (std::size_t m = 0; m + 1 < order; ++m) ds[base + m] = s[base + m + 1];
        ds[base + order - 1] = c_[j * q_count + q];
      }
    }
  }

  struct Source {
    enum class Kind { state, definition, column } kind = Kind::state;
    ir::Signal::Hold hold = ir::Signal::Hold::smooth;  // of a column
    std::size_t slot = 0, index = 0;
    PointSum definition;
    const Column* column = nullptr;  // a recorded input's samples, in the options
    std::vector<double> owned;                    // or its estimated derivative
    std::span<const double> values() const { return column ? std::span<const double>(*column) : std::span<const double>(owned); }
    // The last value read and where: RK4's two middle stages read the same instant.
    mutable double last_t = std::numeric_limits<double>::quiet_NaN(), last_value = 0;
    mutable std::size_t last_interval = 0;
    mutable std::size_t hint = 0;  // interpolate_cubic's
  };
  // A recorded input at t, within the current interval for a held or linear one.
  double recorded(const Source& s, double t) const {
    const Column& time = options_->time;
    const std::size_t k = interval_;
    if (t == s.last_t && k == s.last_interval) return s.last_value;
    const std::span<const double> v = s.values();
    double value = kNaN;
    switch (s.hold) {
      case ir::Signal::Hold::smooth: value = interpolate_cubic(time, v, t, s.hint); break;
      case ir::Signal::Hold::held: value = v[k]; break;
      case ir::Signal::Hold::linear:
        value = time.size() < 2 ? v[0] : v[k] + (v[k + 1] - v[k]) * (t - time[k]) / (time[k + 1] - time[k]);
        break;
    }
    s.last_t = t, s.last_interval = k, s.last_value = value;
    return value;
  }

  const ExplicitForm* form_ = nullptr;
  const SimulateOptions* options_ = nullptr;
  PointLayout layout_;
  PointCompileOptions compile_options_;
  std::vector<std::vector<Weighted>> coefficient_;
  std::vector<Weighted> rest_;
  bool sensitivities_ = false;
  std::size_t parameters_ = 0;
  std::vector<std::vector<std::vector<Weighted>>> coefficient_partial_;  // [i][j][state component]
  std::vector<std::vector<Weighted>> rest_partial_;                      // [i][state component]
  std::vector<std::vector<Weighted>> coefficient_nonlinear_;  // [i][j]: one part per nonlinear parameter
  std::vector<Weighted> rest_nonlinear_;                      // [i]: the same
  bool diagonal_ = false;  // every equation holds only its own output's highest derivative
  Eigen::MatrixXd a_;  // the coefficients of the highest derivatives, and the sensitivity equations' right-hand side
  Eigen::VectorXd z_;      // the highest derivatives
  std::vector<double> g_, c_;  // the sensitivity equations' d(A z + r)/dx (k x n) and right-hand side (k x Q), row-major
  std::vector<PointSum> switching_;
  std::vector<signed char> modes_;  // frozen modes of the current step (freeze())
  std::vector<double> frozen_values_;  // freeze()'s switching values, kept to spare an allocation per step
  bool frozen_ = false;
  std::vector<std::vector<PointSum>> switching_partial_;  // [function][state component], with sensitivities
  std::vector<std::vector<std::pair<std::size_t, PointSum>>> switching_nonlinear_;  // [function]: (parameter, d g / d parameter)
  std::vector<Source> sources_;
  std::vector<double> slots_;
  std::optional<double> initial_det_;
  double last_det_ = 0;
  std::size_t interval_ = 0;  // of options_->time, for held and linear inputs
};

using State = std::vector<double>;

// One classic RK4 step (the thesis' solver, Ralston and Wilf pp. 110-120).
bool rk4_step(System& system, double t, const State& s, double h, State& out, State (&k)[4], State& tmp) {
  const std::size_t n = s.size();
  if (!system.derivative(t, s.data(), k[0].data())) return false;
  for (std::size_t i = 0; i < n; ++i) tmp[i] = s[i] + 0.5 * h * k[0][i];
  if (!system.derivative(t + 0.5 * h, tmp.data(), k[1].data())) return false;
  for (std::size_t i = 0; i < n; ++i) tmp[i] = s[i] + 0.5 * h * k[1][i];
  if (!system.derivative(t + 0.5 * h, tmp.data(), k[2].data())) return false;
  for (std::size_t i = 0; i < n; ++i) tmp[i] = s[i] + h * k[2][i];
  if (!system.derivative(t + h, tmp.data(), k[3].data())) return false;
  for (std::size_t i = 0; i < n; ++i) out[i] = s[i] + h / 6.0 * (k[0][i] + 2 * k[1][i] + 2 * k[2][i] + k[3][i]);
  return true;
}

bool any_sign_change(const std::vector<double>& a, const std::vector<double>& b) {
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i] * b[i] < 0) return true;
  return false;
}

// The first offending state component, or nullopt when the state is fine.
// `scale`: SimulateOptions::state_scale (empty: 1).
std::optional<std::string> divergence(const State& s, const ExplicitForm& form, const std::vector<std::size_t>& offsets, double bound,
                                      const std::vector<double>& scale, double t) {
  for (std::size_t j = 0; j < form.outputs.size(); ++j)
    for (int m = 0; m < form.outputs[j].order; ++m) {
      const std::size_t i = offsets[j] + static_cast<std::size_t>(m);
      const double v = s[i], limit = scale.empty() ? bound : bound * scale[i];
      if (std::abs(v) <= limit) continue;  // the name is made only for a bad one: this runs every step
      const std::string name = prime(form.outputs[j].name, m);
      if (!std::isfinite(v)) return fmt::format("the simulation diverged: `{}` is not finite at t = {:.6g}", name, t);
      if (scale.empty()) return fmt::format("the simulation diverged: |{}| = {:.3g} exceeds {:.3g} at t = {:.6g}", name, std::abs(v), bound, t);
      return fmt::format("the simulation diverged: |{}| = {:.3g} exceeds {:.3g} times its size on the record ({:.3g}) at t = {:.6g}", name,
                         std::abs(v), bound, scale[i], t);
    }
  return std::nullopt;
}

}  // namespace

bool SimulateOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string text) {
    if (why) *why = std::move(text);
    return false;
  };
  if (substeps < 1) return fail("substeps must be at least 1");
  if (!(absolute_tolerance > 0) || !(relative_tolerance >= 0)) return fail("tolerances must be positive");
  if (time.empty()) return fail("no time grid to simulate on");
  for (std::size_t i = 1; i < time.size(); ++i)
    if (!(time[i] > time[i - 1])) return fail(fmt::format("the time grid does not increase at t = {}", time[i]));
  for (const auto& [name, v] : inputs)
    if (v.size() != time.size()) return fail(fmt::format("input `{}` has {} values for {} times", name, v.size(), time.size()));
  if (!(divergence_bound > 0)) return fail("the divergence bound must be positive");
  for (double x : state_scale)
    if (!(x > 0) || !std::isfinite(x)) return fail("a state scale must be a positive number");
  return true;
}

SimulateOptions SimulateOptions::first_samples(std::size_t n) const { return samples(0, n); }

SimulateOptions SimulateOptions::samples(std::size_t first, std::size_t last) const {
  SimulateOptions out;
  out.method = method;
  out.substeps = substeps;
  out.stepper = stepper;
  out.absolute_tolerance = absolute_tolerance;
  out.relative_tolerance = relative_tolerance;
  out.locate_switches = locate_switches;
  out.divergence_bound = divergence_bound;
  out.state_scale = state_scale;
  out.parameters = parameters;
  out.initial = initial;
  const std::size_t end = std::min(last, time.size()), begin = std::min(first, end);
  const auto cut = [&](std::span<const double> values) {
    const std::size_t b = std::min(begin, values.size()), e = std::min(end, values.size());
    return std::vector<double>(values.begin() + static_cast<std::ptrdiff_t>(b), values.begin() + static_cast<std::ptrdiff_t>(e));
  };
  out.time = cut(time);
  for (const auto& [name, values] : inputs) out.inputs[name] = cut(values);
  out.t0_for_tau = t0_for_tau;
  out.initial_value = initial_value;
  out.sensitivities = sensitivities;
  out.progress = progress;
  return out;
}

std::string SimulationSummary::brief_report() const {
  const double first = time.empty() ? 0.0 : time.front(), last = time.empty() ? 0.0 : time.back();
  std::string out = status == Status::completed ? fmt::format("simulation: completed from t = {:.6g} to {:.6g}", first, last)
                                                : fmt::format("simulation: stopped at t = {:.6g} (of {:.6g} to {:.6g})", stopped_at.value_or(first), first, last);
  out += fmt::format(", {} steps, {} evaluations of the equations", steps, right_hand_sides);
  if (switches) out += fmt::format(", {} guard switches located", switches);
  return out;  // `message` says why it stopped; callers print it as an error or a statement
}

std::optional<Diagnostic> simulate_into(const ir::Model& normalized, const ExplicitForm& form, const SimulateOptions& o, SimulationSummary& summary) {
  // Options are the caller's to check (SimulateOptions::is_valid): a bad one here is a bug.
  if (std::string why; !o.is_valid(&why)) throw std::logic_error("simulate: " + why);
  if (o.parameters.size() != normalized.parameters.size())
    throw std::logic_error(fmt::format("simulate: {} parameter values for {} parameters", o.parameters.size(), normalized.parameters.size()));
  // Nonlinear parameters (`sin(L*theta)`) become numbers for the run; the sensitivities to them
  // come from the form that still holds them.
  const bool nonlinear = has_nonlinear_parameters(normalized);
  const ExplicitForm substituted = nonlinear ? substitute_nonlinear(form, normalized, o.parameters) : ExplicitForm{};
  System system;
  if (auto d = system.build(normalized, nonlinear ? substituted : form, o, nonlinear ? &form : nullptr)) return *d;
  // The summary's arrays are refilled in place: a refinement runs the same record dozens of times,
  // and fresh arrays of its size cost more in page faults than the run in arithmetic.
  {
    auto time = std::move(summary.time);
    auto outputs = std::move(summary.outputs);
    auto sensitivity = std::move(summary.sensitivity);
    summary = SimulationSummary{};
    summary.time = std::move(time);
    summary.outputs = std::move(outputs);
    summary.sensitivity = std::move(sensitivity);
  }
  if (o.time.is_borrowed()) summary.time = o.time;  // the record's samples, shared
  else summary.time.owned().assign(o.time.begin(), o.time.end());
  const std::size_t n = o.time.size();
  summary.outputs.resize(form.outputs.size());
  for (std::size_t j = 0; j < form.outputs.size(); ++j) {
    summary.output_names.push_back(form.outputs[j].name);
    summary.outputs[j].assign(n, kNaN);
  }
  State s = state_vector(form, o.initial);
  s.resize(system.vector_size(), 0.0);
  const std::size_t n_state = system.state_size(), columns = system.sensitivity_columns();
  if (!o.state_scale.empty() && o.state_scale.size() != n_state)
    throw std::logic_error(fmt::format("simulate: {} state scales for {} state components", o.state_scale.size(), n_state));
  summary.sensitivity_columns = columns;
  if (!columns) summary.sensitivity.clear();
  if (columns) {
    // d x(t0) / d x0 = I: the initial state's columns follow the parameters'.
    for (std::size_t m = 0; m < n_state; ++m) s[n_state + (o.parameters.size() + m) * n_state + m] = 1;
    summary.sensitivity.resize(form.outputs.size());
    for (auto& column : summary.sensitivity) column.assign(n * columns, kNaN);
  }
  summary.final_vector.clear();
  auto record = [&](std::size_t row, const State& x) {
    if (row + 1 == n) summary.final_vector.assign(x.begin(), x.end());
    for (std::size_t j = 0; j < form.outputs.size(); ++j) {
      summary.outputs[j][row] = x[system.state_offset_[j]];
      for (std::size_t q = 0; q < columns; ++q) summary.sensitivity[j][row * columns + q] = x[n_state + q * n_state + system.state_offset_[j]];
    }
  };
  auto stop = [&](SimulationSummary::Status status, std::string message, double t) {
    summary.status = status;
    summary.message = std::move(message);
    summary.stopped_at = t;
  };
  record(0, s);
  if (auto bad = divergence(s, form, system.state_offset_, o.divergence_bound, o.state_scale, o.time[0])) {
    stop(SimulationSummary::Status::diverged, *bad, o.time[0]);
    return std::nullopt;
  }

  if (o.method == SimulateOptions::Method::rk4) {
    State next(s.size()), tmp(s.size()), trial(s.size());
    State k[4] = {State(s.size()), State(s.size()), State(s.size()), State(s.size())};
    std::vector<double> g0, g1;
    const bool locate = o.locate_switches && system.has_switches();
    for (std::size_t row = 1; row < n; ++row) {
      system.set_interval(row - 1);
      const double h = (o.time[row] - o.time[row - 1]) / o.substeps;
      for (int sub = 0; sub < o.substeps; ++sub) {
        double t = o.time[row - 1] + sub * h;
        const double end = sub + 1 == o.substeps ? o.time[row] : t + h;
        int located = 0;
        while (t < end) {
          double step = end - t;
          if (locate) {  // every stage of this step in the modes it starts in
            system.switching_values(t, s.data(), g0);
            system.freeze(g0);
          }
          bool ok = rk4_step(system, t, s, step, next, k, tmp);
          if (ok && locate && located < 16) {
            system.switching_values(t + step, next.data(), g1);
            if (any_sign_change(g0, g1)) {
              // Bisection on the step length: the shortest step after which a guard has switched.
              double lo = 0, hi = step;
              while (hi - lo > 1e-13 * std::max(1.0, std::abs(t)) && ok) {
                const double mid = 0.5 * (lo + hi);
                ok = rk4_step(system, t, s, mid, trial, k, tmp);
                system.switching_values(t + mid, trial.data(), g1);
                (any_sign_change(g0, g1) ? hi : lo) = mid;
              }
              if (ok) ok = rk4_step(system, t, s, hi, next, k, tmp);
              if (ok && system.sensitivity_columns() > 0 && rk4_step(system, t, s, lo, trial, k, tmp))
                system.jump_sensitivities(t + lo, trial, t + hi, next);
              step = hi;
              ++located;
              ++summary.switches;
            }
          }
          if (!ok) {
            stop(SimulationSummary::Status::singular, *system.trouble, system.trouble_time);
            summary.right_hand_sides = system.evaluations;
            return std::nullopt;
          }
          s.swap(next);
          t = step == end - t ? end : t + step;
          ++summary.steps;
          if (auto bad = divergence(s, form, system.state_offset_, o.divergence_bound, o.state_scale, t)) {
            stop(SimulationSummary::Status::diverged, *bad, t);
            summary.right_hand_sides = system.evaluations;
            return std::nullopt;
          }
        }
      }
      record(row, s);
      if (o.progress && (row % 65536 == 0 || row + 1 == n)) o.progress(row + 1, n);
    }
  } else {
    namespace odeint = boost::numeric::odeint;
    // The stepper's state is the state divided by its scale (SimulateOptions::state_scale), the
    // sensitivities of each component by that component's; with no scale, the state itself.
    State scale;
    if (!o.state_scale.empty()) {
      scale.resize(s.size());
      for (std::size_t i = 0; i < s.size(); ++i) scale[i] = o.state_scale[i % n_state];
      for (std::size_t i = 0; i < s.size(); ++i) s[i] /= scale[i];
    }
    State x_of_z(scale.size());
    auto unscaled = [&](const State& z) -> const State& {
      if (scale.empty()) return z;
      for (std::size_t i = 0; i < z.size(); ++i) x_of_z[i] = z[i] * scale[i];
      return x_of_z;
    };
    auto rhs = [&](const State& z, State& dz, double t) {
      if (!system.derivative(t, unscaled(z).data(), dz.data())) std::fill(dz.begin(), dz.end(), kNaN);
      else if (!scale.empty())
        for (std::size_t i = 0; i < dz.size(); ++i) dz[i] /= scale[i];
    };
    const double first_step = n > 1 ? (o.time[1] - o.time[0]) / 10 : 1e-3;
    // An adaptive stepper creeping towards a singularity takes ever smaller steps and never
    // arrives: below this step it has found one.
    auto minimum_step = [&](double t) { return 1e-12 * std::max({1.0, std::abs(t), std::abs(o.time.back() - o.time.front())}); };
    auto too_small = [&](double t) {
      if (system.nearly_singular()) {
        system.singular_at(t);
        return *system.trouble;
      }
      return fmt::format("the simulation diverged: the adaptive stepper's step fell below 1e-12 of the time span at t = {:.6g} "
                         "(the solution is singular or extremely stiff there)", t);
    };
    // A controlled stepper taken row by row, each step clamped to end at the next grid point.
    auto step_rows = [&](auto stepper) {
      double t = o.time[0], dt = first_step;
      for (std::size_t row = 1; row < n; ++row) {
        system.set_interval(row - 1);
        // dopri5 reuses the last stage of a step as the first of the next: at a sample instant a
        // held input jumps, so the next interval starts afresh.
        if constexpr (requires { stepper.reset(); }) stepper.reset();
        while (t < o.time[row]) {
          if (t + dt > o.time[row]) dt = o.time[row] - t;
          if (stepper.try_step(rhs, s, t, dt) == odeint::success) {
            ++summary.steps;
          } else if (dt < minimum_step(t)) {
            const std::string why = too_small(t);
            stop(system.trouble ? SimulationSummary::Status::singular : SimulationSummary::Status::diverged, why, t);
            return;
          }
          if (system.trouble) {
            stop(SimulationSummary::Status::singular, *system.trouble, system.trouble_time);
            return;
          }
          if (auto bad = divergence(unscaled(s), form, system.state_offset_, o.divergence_bound, o.state_scale, t)) {
            stop(SimulationSummary::Status::diverged, *bad, t);
            return;
          }
        }
        t = o.time[row];
        record(row, unscaled(s));
        if (o.progress && (row % 65536 == 0 || row + 1 == n)) o.progress(row + 1, n);
      }
    };
    try {
      if (o.stepper == SimulateOptions::Stepper::dopri5 && system.has_piecewise_inputs()) {
        // Dense output steps across grid points, and so across the jumps and kinks of held and linear inputs.
        step_rows(odeint::make_controlled(o.absolute_tolerance, o.relative_tolerance, odeint::runge_kutta_dopri5<State>()));
      } else if (o.stepper == SimulateOptions::Stepper::dopri5) {
        auto stepper = odeint::make_dense_output(o.absolute_tolerance, o.relative_tolerance, odeint::runge_kutta_dopri5<State>());
        stepper.initialize(s, o.time[0], first_step);
        for (std::size_t row = 1; row < n; ++row) {
          while (stepper.current_time() < o.time[row]) {
            stepper.do_step(rhs);
            ++summary.steps;
            if (stepper.current_time_step() < minimum_step(stepper.current_time()) && stepper.current_time() < o.time[row]) {
              const std::string why = too_small(stepper.current_time());
              stop(system.trouble ? SimulationSummary::Status::singular : SimulationSummary::Status::diverged, why, stepper.current_time());
              summary.right_hand_sides = system.evaluations;
              return std::nullopt;
            }
            if (system.trouble) {
              stop(SimulationSummary::Status::singular, *system.trouble, system.trouble_time);
              summary.right_hand_sides = system.evaluations;
              return std::nullopt;
            }
            if (auto bad = divergence(unscaled(stepper.current_state()), form, system.state_offset_, o.divergence_bound, o.state_scale, stepper.current_time())) {
              stop(SimulationSummary::Status::diverged, *bad, stepper.current_time());
              summary.right_hand_sides = system.evaluations;
              return std::nullopt;
            }
          }
          stepper.calc_state(o.time[row], s);
          record(row, unscaled(s));
          if (o.progress && (row % 65536 == 0 || row + 1 == n)) o.progress(row + 1, n);
        }
      } else {
        step_rows(odeint::make_controlled(o.absolute_tolerance, o.relative_tolerance, odeint::runge_kutta_cash_karp54<State>()));
      }
    } catch (const std::exception& e) {  // Odeint gives up when no step size satisfies the tolerance
      const double t = system.evaluations ? system.trouble_time : o.time[0];
      if (system.trouble) stop(SimulationSummary::Status::singular, *system.trouble, t);
      else stop(SimulationSummary::Status::diverged, fmt::format("the simulation diverged: the adaptive stepper found no step size meeting the tolerance ({})", e.what()), t);
    }
  }
  summary.right_hand_sides = system.evaluations;
  return std::nullopt;
}

std::variant<SimulationSummary, Diagnostic> simulate(const ir::Model& normalized, const ExplicitForm& form, const SimulateOptions& o) {
  SimulationSummary summary;
  if (auto d = simulate_into(normalized, form, o, summary)) return *d;
  return summary;
}

std::vector<double> state_vector(const ExplicitForm& form, const std::map<std::string, std::vector<double>>& initial) {
  std::vector<double> x;
  for (const auto& out : form.outputs) {
    auto it = initial.find(out.name);
    for (int m = 0; m < out.order; ++m) {
      const auto k = static_cast<std::size_t>(m);
      x.push_back(it != initial.end() && k < it->second.size() ? it->second[k] : 0.0);
    }
  }
  return x;
}

std::map<std::string, std::vector<double>> state_map(const ExplicitForm& form, std::span<const double> x) {
  std::map<std::string, std::vector<double>> initial;
  std::size_t k = 0;
  for (const auto& out : form.outputs)
    for (int m = 0; m < out.order && k < x.size(); ++m) initial[out.name].push_back(x[k++]);
  return initial;
}

std::variant<EvaluationOptions, Diagnostic> state_operators_for_record(const ExplicitForm& form, const SampledRecord& record,
                                                                       const EvaluationOptions& evaluation) {
  std::vector<std::pair<std::string, int>> needed;
  for (const auto& out : form.outputs)
    for (int m = 1; m < out.order; ++m) needed.emplace_back(out.name, m);
  return operators_for_record(evaluation, record, ir::Model{}, needed);
}

std::variant<std::map<std::string, std::vector<double>>, Diagnostic> initial_state_from_record(const ExplicitForm& form,
                                                                                              const SampledRecord& record,
                                                                                              const EvaluationOptions& evaluation,
                                                                                              std::size_t index, bool arcs_chosen) {
  std::map<std::string, std::vector<double>> initial;
  auto chosen = arcs_chosen ? std::variant<EvaluationOptions, Diagnostic>(evaluation) : state_operators_for_record(form, record, evaluation);
  if (auto* e = std::get_if<Diagnostic>(&chosen)) return *e;
  const EvaluationOptions& options = std::get<EvaluationOptions>(chosen);
  for (const auto& out : form.outputs) {
    auto column = record.signals.find(out.name);
    if (column == record.signals.end()) return diag::signal_not_in_record(out.span, out.name, record.path);
    std::vector<double> values;
    for (int m = 0; m < out.order; ++m) {
      if (m == 0) {
        values.push_back(column->second[index]);
        continue;
      }
      DerivativeOptions d = derivative_options_for(options, out.name, m);
      d.edges = DerivativeOptions::Edges::shorten;
      // The samples up to the arc's reach past `index` give the same value there as the whole record
      // (a shortened edge only moves stencils within the reach of the end): no whole-record pass for one value.
      const std::size_t reach = MovingArcOperator(m, d).reach().value_or(column->second.size());
      const std::size_t needed = std::min(column->second.size(), index + reach + 1);
      auto estimate = estimate_derivative(std::span<const double>(column->second).first(needed), record.step, m, d);
      if (auto* e = std::get_if<Diagnostic>(&estimate)) return *e;
      values.push_back(std::get<std::vector<double>>(estimate)[index]);
    }
    initial[out.name] = std::move(values);
  }
  return initial;
}

}  // namespace sidc
