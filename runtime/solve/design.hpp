// The design matrix of one group of equations (thesis section 2-1: each operation op_k of the
// linear form sum_k a_k op_k = known, eq. 2-1.2, evaluated on the record; one row per sample and
// equation, one column per parameter, the known side beside it, rows weighted by eq. 2-1.6), laid
// out and filled one way for the dense fit, the streamed fit (runtime/solve/fit.cpp) and select
// (runtime/select/select.cpp).
//
// Relies on: a compiled model and its records bound to signals (bind_record.hpp); the operations'
// values from an evaluator behind DesignValues: Evaluator on whole fit windows (evaluate.hpp) or
// BlockEvaluator on row blocks (block_evaluator.hpp). Guarantees:
// - Columns: every parameter the group's equations use, once, in the model's parameter order;
//   with several records an integration constant once per record, its columns side by side
//   (`C1@2` is record 2's). Each column carries its ParameterIndex beside its name, and label()
//   puts it on the solved estimates, so nobody looks a parameter up by name again.
// - Rows: equation_rows() writes each term's operation into its parameter's column and the known
//   side into b, as the evaluator gives them, with no arithmetic, so callers with the same
//   evaluator get the same bits; window_rows() lays out a record's whole window equation by
//   equation, time increasing (the dense fit's row order).
// - Weights (eq. 2-1.6): the record's weight column times the value of `set weights`, which must
//   be finite and >= 0 on every row (check_weights names the first row that is not).
// - A value that is not finite is a Diagnostic naming the term, its owner and the time: from
//   Evaluator::evaluate_in_window on whole windows, from non_finite_value for a row block.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"
#include "runtime/operators/block_evaluator.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/solve/least_squares.hpp"

namespace sidc {

struct DesignColumn {
  std::string name;      // the parameter's name; `C1@2` for record 2's own integration constant
  ParameterIndex index;  // the model parameter (and record) the column estimates
};

// Where the builder's values come from: one sum of the design over the rows being filled.
class DesignValues {
 public:
  virtual ~DesignValues() = default;
  // `sum` on the rows into `out`, one value per row. `index` is the sum's place in its equation
  // (term k's operation: k; the known side: the number of terms), the order in which the dense
  // path meets problems; `what` names its owner for messages ("the operation of `a1`"). A
  // Diagnostic stops the rows.
  virtual std::optional<Diagnostic> evaluate(const ir::Sum& sum, std::size_t index, const std::string& what,
                                             std::span<double> out) = 0;
};

// Whole fit windows (the dense fit, select): Evaluator::evaluate_in_window, which stops at the
// first value that is not finite, by term, then by time.
class WindowValues final : public DesignValues {
 public:
  explicit WindowValues(Evaluator& evaluator) : evaluator_(evaluator) {}
  std::optional<Diagnostic> evaluate(const ir::Sum& sum, std::size_t index, const std::string& what,
                                     std::span<double> out) override;

 private:
  Evaluator& evaluator_;
};

// Rows being filled: column-major, the parameters' columns and the known side apart (the dense
// design keeps b beside A; a streamed block is the accumulator's [A b] work area).
struct DesignBlock {
  Eigen::Ref<Eigen::MatrixXd> A;  // m x p; columns of parameters the equation does not use are left as they are
  Eigen::Ref<Eigen::VectorXd> b;  // m
};

class DesignBuilder {
 public:
  // The design of the group `equations` (indices into the model's equations) over `records`;
  // the model and the records must outlive the builder.
  DesignBuilder(const ir::Model& model, const std::vector<SampledRecord>& records, std::vector<std::size_t> equations);

  const std::vector<DesignColumn>& columns() const { return columns_; }
  std::vector<std::string> column_names() const;
  std::vector<ParameterIndex> column_indices() const;
  // The column of `parameter` (index into the model's parameters) in the rows of `record`.
  std::size_t column(int parameter, std::size_t record) const;
  // Every operation and known side of the group, equation by equation (what the whole-window
  // values of a row-block evaluator must cover).
  std::vector<const ir::Sum*> sums() const;

  // The rows of `equation` for `record`: each term's operation into its parameter's column of
  // rows.A, the known side into rows.b, all through `values`, in term order, the known side last.
  std::optional<Diagnostic> equation_rows(std::size_t record, std::size_t equation, DesignValues& values,
                                          DesignBlock rows) const;

  // `record`'s whole fit window (the evaluator's), every equation of the group in turn, time
  // increasing, into rows [row, row + equations x window) of A, b and weights; `expression` is the
  // record's `set weights` on the window (expression_weights), empty when the model sets none.
  // weights is written only where the record is weighted (eq. 2-1.6).
  std::optional<Diagnostic> window_rows(std::size_t record, Evaluator& evaluator, std::span<const double> expression,
                                        Eigen::MatrixXd& A, Eigen::VectorXd& b, Eigen::VectorXd& weights,
                                        Eigen::Index row) const;

  // eq. 2-1.6: the weights of `record`'s rows from sample first_sample on: its weight column
  // times `expression` (`set weights` on those rows; empty when the model sets none). Null when
  // neither is given (the rows are unweighted); the weight column itself when only it is; else
  // `out` (at least expression.size() long; it may be `expression`) holding the products.
  const double* row_weights(std::size_t record, std::size_t first_sample, std::span<const double> expression,
                            std::span<double> out) const;

  // Fewer rows than columns: the window is too short for the group (the records' first named).
  std::optional<Diagnostic> too_few_rows(std::size_t rows, const EvaluationOptions& options) const;

  // Puts each column's ParameterIndex on the estimates solved from this design.
  void label(LeastSquaresSummary& summary) const;

 private:
  const ir::Model& model_;
  const std::vector<SampledRecord>& records_;
  std::vector<std::size_t> equations_;
  std::vector<DesignColumn> columns_;
  std::vector<std::size_t> first_column_;  // per model parameter: its (first) column
  std::vector<char> per_record_;           // per model parameter: a column per record
  std::vector<std::string> owner_;         // per model parameter: "the operation of `a1`"
};

// `set weights = <expression>` (eq. 2-1.6) on the evaluator's fit window: one weight per row, or
// a Diagnostic at the `set weights` line when a value is negative, NaN or infinite.
std::variant<std::vector<double>, Diagnostic> expression_weights(const ir::Model& model, Evaluator& evaluator);

// The first of `values` (`set weights` on `record`'s samples from first_sample on) that is not a
// finite number >= 0, as a Diagnostic at the `set weights` line; nullopt when all are.
std::optional<Diagnostic> check_weights(const ir::Model& model, const SampledRecord& record, std::span<const double> values,
                                        std::size_t first_sample);

// A row block's value that is not finite (block_evaluator.hpp's report) in the words the
// whole-window evaluator uses: the term alone, its owner `what`, the time and the record.
Diagnostic non_finite_value(const SampledRecord& record, const ir::Sum& sum, NonFiniteValue bad, const std::string& what);

}  // namespace sidc
