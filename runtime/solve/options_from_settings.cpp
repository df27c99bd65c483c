#include "runtime/solve/options_from_settings.hpp"

namespace sidc {

EvaluationOptions evaluation_options(const EvaluationSettings& e) {
  EvaluationOptions o;
  o.derivative.window = e.derivative.window;
  o.derivative.polyorder = e.derivative.order;
  o.automatic_derivative = e.derivative.automatic;
  o.second_given = e.second_derivative_given;
  o.derivative.second = e.second_derivative_repeated ? DerivativeOptions::Second::repeated : DerivativeOptions::Second::direct;
  o.derivative.edges = e.shorten_edges ? DerivativeOptions::Edges::shorten : DerivativeOptions::Edges::drop;
  o.integration.rule = e.trapezoid ? IntegrationOptions::Rule::trapezoid : IntegrationOptions::Rule::simpson;
  if (e.smooth_before_integration) {
    o.integration.smoothing_window = e.smooth_before_integration->window;
    o.integration.smoothing_polyorder = e.smooth_before_integration->order;
  }
  return o;
}

FitOptions fit_options(const EvaluationSettings& e) {
  FitOptions o;
  o.evaluation = evaluation_options(e);
  o.from = e.from;
  o.to = e.to;
  o.weak_covariance = e.weak_covariance;
  return o;
}

BindOptions bind_options(const EvaluationSettings& e) {
  BindOptions b;
  b.every = e.every;
  b.step = e.step;
  b.weights = e.weights;
  return b;
}

}  // namespace sidc
