// The design of weak-form equations (compiler/weak_pass.hpp): one row per subdomain of each
// record, each operation integrated against the test function of that subdomain.
//
// Relies on: design.hpp (columns, the rows of an equation through DesignValues), evaluate.hpp
// (each phi-free part of an operation on the whole fit window), test_functions.hpp (the subdomains
// chosen from the record, the quadrature weights). Guarantees: an operation sum_k phi_j^(k) * g_k
// gives row j the value sum_k integral(phi_j^(k) * g_k), each g_k evaluated once per record; the
// rows run record by record, equation by equation, subdomain centres increasing (the times given
// are the centres); a weighted row (eq. 2-1.6) carries the phi-weighted mean of its samples' weights,
// or 0 when one of them is 0 (a masked sample takes out every subdomain it lies in).
// The weak design has few rows (about 4 n / m), so it is always solved dense; each g_k is evaluated
// block by block (memory of a block, not of the record; held or linear inputs: on the whole window).
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/operators/test_functions.hpp"
#include "runtime/solve/design.hpp"
#include "runtime/solve/row_share.hpp"

namespace sidc {

// True when the group's equations are of the weak form; a Diagnostic when they mix forms (their
// rows would not be commensurable: samples against subdomains).
std::variant<bool, Diagnostic> is_weak_group(const ir::Model& model, const std::vector<std::size_t>& equations);

// A weak operation sum_k phi_j^(k) * g_k as its parts g_k, by the order k of the test function.
std::map<int, ir::Sum> parts_by_test_function(const ir::Sum& s);

// sum_i a[i] * b[i] over n values, summed in a fixed order (the same result on every run and thread).
double running_dot(const double* a, const double* b, std::size_t n);

// sum_i w[i] * x[i] over a support (w.size() values from x): each row's integral, summed in a fixed
// order, so that the result is the same on every run and thread.
double support_dot(const std::vector<double>& w, const double* x);

// Row j of an operation: its integral against subdomain j's test function (see above).
class WeakValues final : public DesignValues {
 public:
  // With a share of more than one part (FitOptions::share), each part integrates the subdomains
  // whose supports start in its share of the window's blocks, and the parts' rows are summed
  // (row_share.hpp): the rows one process computes, bit for bit.
  WeakValues(Evaluator& evaluator, const TestFunctionGrid& grid, RowShare* share = nullptr);
  std::optional<Diagnostic> evaluate(const ir::Sum& sum, std::size_t index, const std::string& what,
                                     std::span<double> out) override;

 private:
  // out[j] += integral(phi_j^(k) g) for every row, g evaluated block by block (block_evaluator.hpp:
  // Evaluator's values bit for bit) on the blocks' threads: memory of a block, not of the window.
  // Only the rows whose supports start in window blocks [first_block, last_block).
  std::optional<Diagnostic> add_rows(const ir::Sum& g, const std::string& what, const std::vector<double>& w, std::span<double> out,
                                     std::size_t first_block = 0, std::size_t last_block = SIZE_MAX);
  // add_rows with the blocks shared among share_'s parts.
  std::optional<Diagnostic> add_shared_rows(const ir::Sum& g, const std::string& what, const std::vector<double>& w, std::span<double> out);

  Evaluator& evaluator_;
  const TestFunctionGrid& grid_;
  std::vector<std::vector<double>> weights_;  // per derivative order of phi, made when first asked for
  RowShare* share_ = nullptr;
};

struct WeakDesign {
  Eigen::MatrixXd A;
  Eigen::VectorXd b, weights;
  std::vector<std::size_t> row_equation, row_record;
  std::vector<double> row_time;
  std::vector<TestFunctionGrid> grids;  // per record
};

// The weak design of `design`'s group on record `r` alone (its evaluator on its window):
// `expression` is `set weights` on the window as fit.cpp computes it (empty when the model sets none).
// Its subdomains are chosen from the record (choose_test_functions), or `given` (a fit made again on
// changed data with the first one's choices: noise_check.hpp).
std::variant<WeakDesign, Diagnostic> weak_record_design(const ir::Model& model, const std::vector<SampledRecord>& records, std::size_t r,
                                                        Evaluator& evaluator, const DesignBuilder& design,
                                                        const std::vector<std::size_t>& equations, std::span<const double> expression,
                                                        RowShare* share = nullptr, const TestFunctionGrid* given = nullptr);

// The weak design of `design`'s group over every record (each evaluator on its record's window),
// the records' rows stacked; `expression_weights` per record (empty when the model sets none).
std::variant<WeakDesign, Diagnostic> weak_design(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                 std::vector<Evaluator>& evaluators, const DesignBuilder& design,
                                                 const std::vector<std::size_t>& equations,
                                                 const std::vector<std::vector<double>>& expression_weights, RowShare* share = nullptr,
                                                 const std::vector<TestFunctionGrid>* given = nullptr);

// One line for the report: "42 subdomains of 2*48+1 samples, phi = (1 - s^2)^6; <reason>".
std::string describe(const TestFunctionGrid& grid, double step);

}  // namespace sidc
