// The registry: which SignalOperator an evaluation's options choose (see signal_operator.hpp).
#include "runtime/operators/signal_operator.hpp"

#include "runtime/operators/evaluate.hpp"
#include "runtime/operators/savitzky_golay.hpp"
#include "runtime/operators/simpson.hpp"

namespace sidc {

std::unique_ptr<const SignalOperator> derivative_operator(const EvaluationOptions& options, int order, const std::string& signal) {
  return std::make_unique<MovingArcOperator>(order, derivative_options_for(options, signal, order));
}

std::unique_ptr<const SignalOperator> integral_operator(const EvaluationOptions& options) {
  return std::make_unique<CumulativeIntegralOperator>(options.integration);
}

}  // namespace sidc
