// The design builder (see design.hpp).
//
// Relies on: evaluate.hpp (Evaluator::evaluate_in_window, fit_window's loss at the edges),
// data_catalogue.hpp for every message. Guarantees: the header's; nothing here does arithmetic
// on an operation's value, so the dense fit, the streamed fit and select keep the bits their
// evaluators give, and the only product is a row's weight (eq. 2-1.6).
#include "runtime/solve/design.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include <fmt/format.h>

#include "diagnostics/data_catalogue.hpp"
#include "ir/print.hpp"
#include "ir/queries.hpp"

namespace sidc {

namespace {

const std::string kKnownSide = "the known side";

}  // namespace

std::optional<Diagnostic> WindowValues::evaluate(const ir::Sum& sum, std::size_t, const std::string& what, std::span<double> out) {
  auto values = evaluator_.evaluate_in_window(sum, what);
  if (auto* d = std::get_if<Diagnostic>(&values)) return std::move(*d);
  const auto& v = std::get<std::vector<double>>(values);
  std::copy(v.begin(), v.end(), out.begin());
  return std::nullopt;
}

DesignBuilder::DesignBuilder(const ir::Model& model, const std::vector<SampledRecord>& records, std::vector<std::size_t> equations)
    : model_(model),
      records_(records),
      equations_(std::move(equations)),
      first_column_(model.parameters.size(), 0),
      per_record_(model.parameters.size(), 0),
      owner_(model.parameters.size()) {
  std::set<int> used;
  for (std::size_t e : equations_)
    for (const auto& term : model.equations[e].terms) used.insert(term.parameter);
  for (int p : used) {
    const auto k = static_cast<std::size_t>(p);
    const ir::Parameter& parameter = model.parameters[k];
    // Each record starts its own integrals at its own t0, so each has its own constants (eq. 2-2.4).
    per_record_[k] = parameter.origin == ir::Parameter::Origin::integration_constant && records.size() > 1;
    first_column_[k] = columns_.size();
    owner_[k] = "the operation of `" + parameter.name + "`";
    if (!per_record_[k]) {
      columns_.push_back({parameter.name, {k, std::nullopt}});
      continue;
    }
    for (std::size_t r = 0; r < records.size(); ++r) columns_.push_back({fmt::format("{}@{}", parameter.name, r + 1), {k, r}});
  }
}

std::vector<std::string> DesignBuilder::column_names() const {
  std::vector<std::string> names;
  for (const auto& c : columns_) names.push_back(c.name);
  return names;
}

std::vector<ParameterIndex> DesignBuilder::column_indices() const {
  std::vector<ParameterIndex> indices;
  for (const auto& c : columns_) indices.push_back(c.index);
  return indices;
}

std::size_t DesignBuilder::column(int parameter, std::size_t record) const {
  const auto k = static_cast<std::size_t>(parameter);
  return first_column_[k] + (per_record_[k] ? record : 0);
}

std::vector<const ir::Sum*> DesignBuilder::sums() const {
  std::vector<const ir::Sum*> sums;
  for (std::size_t e : equations_) {
    for (const auto& term : model_.equations[e].terms) sums.push_back(&term.operation);
    sums.push_back(&model_.equations[e].known);
  }
  return sums;
}

std::optional<Diagnostic> DesignBuilder::equation_rows(std::size_t record, std::size_t equation, DesignValues& values,
                                                       DesignBlock rows) const {
  const ir::Equation& eq = model_.equations[equation];
  const auto m = static_cast<std::size_t>(rows.b.size());
  for (std::size_t k = 0; k < eq.terms.size(); ++k) {
    const ir::ParameterTerm& term = eq.terms[k];
    const auto c = static_cast<Eigen::Index>(column(term.parameter, record));
    if (auto problem = values.evaluate(term.operation, k, owner_[static_cast<std::size_t>(term.parameter)],
                                       std::span<double>(rows.A.col(c).data(), m)))
      return problem;
  }
  return values.evaluate(eq.known, eq.terms.size(), kKnownSide, std::span<double>(rows.b.data(), m));
}

std::optional<Diagnostic> DesignBuilder::window_rows(std::size_t record, Evaluator& evaluator, std::span<const double> expression,
                                                     Eigen::MatrixXd& A, Eigen::VectorXd& b, Eigen::VectorXd& weights,
                                                     Eigen::Index row) const {
  const FitWindow& w = evaluator.window();
  const auto n = static_cast<Eigen::Index>(w.size());
  std::vector<double> products(expression.size());
  const double* row_weight = row_weights(record, w.first, expression, products);
  WindowValues values(evaluator);
  for (std::size_t e : equations_) {
    if (auto problem = equation_rows(record, e, values, {A.middleRows(row, n), b.segment(row, n)})) return problem;
    if (row_weight) weights.segment(row, n) = Eigen::Map<const Eigen::VectorXd>(row_weight, n);
    row += n;
  }
  return std::nullopt;
}

const double* DesignBuilder::row_weights(std::size_t record, std::size_t first_sample, std::span<const double> expression,
                                         std::span<double> out) const {
  const std::vector<double>& column = records_[record].weights;
  const double* own = column.empty() ? nullptr : column.data() + first_sample;
  if (expression.empty()) return own;
  if (!own) return expression.data();
  for (std::size_t i = 0; i < expression.size(); ++i) out[i] = own[i] * expression[i];
  return out.data();
}

std::optional<Diagnostic> DesignBuilder::too_few_rows(std::size_t rows, const EvaluationOptions& options) const {
  if (rows >= columns_.size()) return std::nullopt;
  return diag::window_too_short(records_.front().path, rows, columns_.size(),
                                options.automatic_derivative
                                    ? samples_lost_by_model(model_, options)
                                    : samples_lost_each_side(std::max(1, highest_derivative_order(model_)), options.derivative));
}

void DesignBuilder::label(LeastSquaresSummary& summary) const {
  for (std::size_t j = 0; j < summary.parameters.size() && j < columns_.size(); ++j) summary.parameters[j].index = columns_[j].index;
}

std::variant<std::vector<double>, Diagnostic> expression_weights(const ir::Model& model, Evaluator& evaluator) {
  auto values = evaluator.evaluate(model.weights->value);
  if (auto* d = std::get_if<Diagnostic>(&values)) return *d;
  const auto& v = std::get<std::vector<double>>(values);
  const FitWindow& w = evaluator.window();
  std::vector<double> window(v.begin() + static_cast<std::ptrdiff_t>(w.first), v.begin() + static_cast<std::ptrdiff_t>(w.first + w.size()));
  if (auto problem = check_weights(model, evaluator.record(), window, w.first)) return *problem;
  return window;
}

std::optional<Diagnostic> check_weights(const ir::Model& model, const SampledRecord& record, std::span<const double> values,
                                        std::size_t first_sample) {
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i]) || values[i] < 0)
      return diag::weight_not_valid(model.weights->span, print(model.weights->value), values[i], record.time[first_sample + i], record.path);
  return std::nullopt;
}

Diagnostic non_finite_value(const SampledRecord& record, const ir::Sum& sum, NonFiniteValue bad, const std::string& what) {
  const ir::Term& t = sum.terms[bad.term];
  const ir::Sum single = ir::canonical(std::vector<ir::Term>{t});
  return diag::operation_not_finite(t.span, print(single), what, record.time[bad.sample], record.path);
}

}  // namespace sidc
