#include "runtime/operators/plot_function.hpp"

#include <array>
#include <limits>

#include "diagnostics/model_catalogue.hpp"
#include "runtime/operators/point_evaluator.hpp"

namespace sidc {
namespace {

std::string curve_argument(const ir::PlotFunction& plot) { return plot.signal + std::string(static_cast<std::size_t>(plot.order), '\''); }

}  // namespace

std::variant<PlotCurve, Diagnostic> evaluate_plot_function(const ir::PlotFunction& plot, const std::vector<double>& parameters,
                                                           double low, double high, int points) {
  // The fitted function as one sum, each operation scaled by its parameter's value.
  ir::Sum fitted = plot.rest;
  for (const auto& [index, operation] : plot.terms) {
    const auto k = static_cast<std::size_t>(index);
    const double value = k < parameters.size() ? parameters[k] : std::numeric_limits<double>::quiet_NaN();
    fitted = ir::add(fitted, ir::scale(operation, Number::real(value)));
  }
  PointLayout layout;
  layout.slot(plot.signal, plot.order);  // slot 0: the argument, the only quantity a plot may use
  auto compiled = compile_point_sum(fitted, layout);
  if (auto* d = std::get_if<Diagnostic>(&compiled)) return *d;
  std::optional<PointSum> truth;
  if (plot.truth) {
    auto t = compile_point_sum(*plot.truth, layout);
    if (auto* d = std::get_if<Diagnostic>(&t)) return *d;
    truth = std::get<PointSum>(std::move(t));
  }
  // The compiler allows only the argument; a damaged compiled file could name more.
  if (layout.size() != 1)
    return diag::plot_uses_other_quantity(plot.span, plot.name, layout.slots()[1].first + std::string(static_cast<std::size_t>(layout.slots()[1].second), '\''),
                                          curve_argument(plot));
  PlotCurve curve;
  curve.name = plot.name;
  curve.argument = curve_argument(plot);
  if (points < 2) points = 2;
  std::array<double, 1> slot{};
  for (int i = 0; i < points; ++i) {
    // Both ends exact: low + i*(high - low)/(points - 1) would miss `high` by rounding.
    const double v = i == points - 1 ? high : low + (high - low) * i / (points - 1);
    slot[0] = v;
    const PointInstant at{slot, 0, 0, {}};
    curve.x.push_back(v);
    curve.fitted.push_back(std::get<PointSum>(compiled).evaluate(at));
    if (truth) curve.truth.push_back(truth->evaluate(at));
  }
  return curve;
}

}  // namespace sidc
