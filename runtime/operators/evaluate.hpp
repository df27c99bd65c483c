// Evaluation of compiled operations on a sampled record, column by column (thesis chapter III).
//
// Relies on: a compiled model (ir/ir.hpp) and a record bound to its signals on a uniform
// time grid. Guarantees: every factor is evaluated over the whole record — derivatives and
// integrals by the SignalOperator the options choose (signal_operator.hpp: the moving arc, eqs.
// 3-1.2 to 3-1.8; cumulative Simpson or trapezoid from the window start t0, eqs. 2-1.4, 2-2.5),
// products, powers, functions and guards sample by sample — with NaN where a value does not exist
// (the edges a derivative loses, before t0 for an integral).
// Each derivative and integral is computed once per record and reused. A value that is NaN or
// infinite inside the fit window is reported with the source span of the operation that made it.
#pragma once

#include <array>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <variant>
#include <utility>
#include <vector>

#include "ir/ir.hpp"
#include "diagnostics/diagnostic.hpp"
#include "runtime/operators/savitzky_golay.hpp"
#include "runtime/operators/signal_operator.hpp"
#include "runtime/operators/simpson.hpp"
#include "runtime/records/sampled_record.hpp"

namespace sidc {

// What chooses and configures the operators (derivative_operator(), integral_operator()).
struct EvaluationOptions {
  // The moving arc of every derivative; under `automatic_derivative`, its edges and (when
  // `second_given`) its way to higher orders still hold, and window and order come from `chosen`.
  DerivativeOptions derivative;
  // `derivative = savgol(auto)`: window and order chosen per signal and per derivative order from
  // one record's data (runtime/operators/operator_choice.hpp fills `chosen` for a record).
  bool automatic_derivative = false;
  bool second_given = false;  // `second_derivative` was written: auto keeps to that way
  // Signal name (or a printed der() factor) -> derivative order -> the arc for one record.
  std::map<std::string, std::map<int, DerivativeOptions>> chosen;
  IntegrationOptions integration;
};

// The arc for the order-th derivative of `signal` (a signal name or a printed der() factor):
// options.derivative, or under savgol(auto) the one chosen for this record. A missing choice under
// auto is a bug of the caller (operators_for_record() was not applied): std::logic_error.
DerivativeOptions derivative_options_for(const EvaluationOptions& options, const std::string& signal, int order);

// The rows a fit uses: [first, last] of the record, with t0 = time[first].
struct FitWindow {
  std::size_t first = 0;
  std::size_t last = 0;  // inclusive
  std::size_t size() const { return last >= first ? last - first + 1 : 0; }
};

// The highest order of derivative any operation of the model estimates (a der() of a derivative
// adds up); the fit window keeps clear of the samples such derivatives lose at each edge.
int highest_derivative_order(const ir::Model& model);

// Samples the model's operations lose at each edge of a record (edges = drop): the half-window of
// the widest operator, counting a der() of a derivative as the sum of the two. Under savgol(auto)
// each signal and order has its own arc.
int samples_lost_by_model(const ir::Model& model, const EvaluationOptions& options);

// One condition of a guard (eq. 4-1.9's regions) sample by sample: where `lhs relation rhs` fails,
// `guard` becomes 0; where either side is NaN (no value there), NaN. Shared by the whole-record
// and block evaluators, so that both draw the regions' borders alike.
void apply_condition(ir::Relation relation, std::span<const double> lhs, std::span<const double> rhs, std::span<double> guard);

// One of the language's functions (sin, cos, exp, log, sqrt, abs, sign, tanh) applied in place;
// the name is resolved once, not per sample. Shared by the whole-record and block evaluators.
void apply_function(const std::string& name, std::span<double> values);

// The window the thesis uses: from the first sample with a full neighbourhood for every
// derivative (t0 = 3*alpha*Delta for the 7-point operator applied alpha times, eq. 4-1.10) to the
// last, cut to [from, to] when given. A Diagnostic when nothing is left.
std::variant<FitWindow, Diagnostic> fit_window(const SampledRecord& record, const ir::Model& model,
                                               const EvaluationOptions& options, std::optional<double> from,
                                               std::optional<double> to);

class Evaluator {
 public:
  Evaluator(const SampledRecord& record, const ir::Model& model, const EvaluationOptions& options, FitWindow window);

  // The sum's value at every sample of the record; NaN where it has none.
  std::variant<std::vector<double>, Diagnostic> evaluate(const ir::Sum& s);
  // The same, cut to the fit window, with an error naming the term if a value in it is not finite;
  // `what` says whose term it is ("the operation of `a1`", "the known side").
  std::variant<std::vector<double>, Diagnostic> evaluate_in_window(const ir::Sum& s, const std::string& what);
  // The same into `total` (its memory reused from call to call: a whole window is 80 MB at 10^7).
  std::optional<Diagnostic> evaluate_in_window(const ir::Sum& s, const std::string& what, std::vector<double>& total);

  const FitWindow& window() const { return window_; }
  const SampledRecord& record() const { return record_; }
  const ir::Model& model() const { return model_; }
  const EvaluationOptions& options() const { return options_; }

  // The model has held or linear inputs: every integral is taken interval by interval, within the
  // segments between the inputs' changes of piece (runtime/operators/piecewise_inputs.hpp).
  bool segmented() const { return segmented_; }
  // The stencil nodes lo..hi (lo in {-1, 0}, hi in {1, 2}) of the interval from sample k to k + 1:
  // the samples around it that lie in the fit window and in its segment.
  std::pair<int, int> interval_nodes(std::size_t k);
  // `s` at each sample as the interval d samples earlier sees it, one array per d of kPieceOffsets
  // (piecewise_inputs.hpp): the terms holding a held or linear input on piece record d, the others
  // once. With `what`, cut to the fit window, a value that is not finite reported as
  // evaluate_in_window() does; without, over the whole record. A Diagnostic for a term with an
  // integral of such an input, whose pieces are not the integral's values.
  using Stencil = std::array<std::vector<double>, 4>;
  std::variant<Stencil, Diagnostic> stencil_values(const ir::Sum& s, const std::string* what = nullptr);

 private:
  using Values = std::vector<double>;
  struct Pieces;  // the four piece records and their evaluators, made on first use
  // Per interval [t_i, t_{i+1}] of the window: int (t_{i+1} - s)^m / m! s(t) dt, exact in held inputs.
  std::variant<Values, Diagnostic> interval_integrals(const ir::Sum& s, int m);
  Evaluator& piece(int d);
  std::variant<Values, Diagnostic> term(const ir::Term& t);
  std::optional<Diagnostic> term_into(const ir::Term& t, Values& v);
  std::variant<Values, Diagnostic> factor(const ir::Factor& f, const Span& where);
  // The factor's values without a copy of what the evaluator keeps (a signal, its derivatives, an
  // integral, a der()): a view of its cache, or of `scratch` where the values are made afresh. A
  // whole record is 80 MB at 10^7 samples: copying each factor of each term dominated weak forms.
  std::variant<std::span<const double>, Diagnostic> factor_view(const ir::Factor& f, const Span& where, Values& scratch);
  std::variant<Values, Diagnostic> signal(const std::string& name, int order, const Span& where);
  std::variant<std::span<const double>, Diagnostic> signal_view(const std::string& name, int order, const Span& where);
  std::variant<double, Diagnostic> initial_value(const ir::Factor& f, const Span& where);

  const SampledRecord& record_;
  const ir::Model& model_;
  EvaluationOptions options_;
  FitWindow window_;
  std::map<std::pair<std::string, int>, Values> derivatives_;  // (signal, order >= 1) -> values
  std::map<std::string, Values> composite_;                    // integrals and der() by printed text
  bool segmented_ = false;
  std::vector<unsigned char> boundaries_;  // piece_boundaries(), made on first use
  std::shared_ptr<Pieces> pieces_;
  Values term_buffer_;  // evaluate_in_window's terms, one after another
  bool term_buffer_busy_ = false;
};

}  // namespace sidc
