// `fit`: the parameters of a compiled model from sampled records, by weighted least squares
// (thesis section 2-1), solved by QR (runtime/least_squares.hpp).
//
// Relies on: a compiled model and its records bound to signals (bind_record.hpp). Guarantees:
// equations that share no parameter are solved separately, equations that share parameters
// jointly (one design matrix, rows stacked); each record contributes its own rows from its own fit
// window, and, when there are several records, its own integration constants (named `C1@2` for
// record 2). Every operation is evaluated on the window (evaluate.hpp); the summary carries the
// least-squares statistics of each group and a report in the shape of the thesis' tables.
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "compiler/ir.hpp"
#include "runtime/evaluate.hpp"
#include "runtime/least_squares.hpp"

namespace sidc {

struct FitOptions {
  EvaluationOptions evaluation;
  LeastSquaresOptions least_squares;
  std::optional<double> from, to;  // fit window in time, for every record
  bool is_valid(std::string* why) const;
};

// The rows one record gave to one group.
struct RecordRows {
  std::string path;
  double t0 = 0, t_last = 0, step = 0;
  std::size_t first_sample = 0, rows = 0;  // rows per equation
};

// Rows of the fit by the combination of guards that hold on them (the thesis' quadrants of the
// phase plane, Table 4-1.1, for eq. 4-1.8's four regions).
struct Region {
  std::string guards;  // e.g. "[y <= 0] and [y' >= 0]"; "(no guard)" when none holds
  std::size_t rows = 0;
};

struct GroupFit {
  std::vector<std::size_t> equations;          // indices into the model's equations
  std::vector<std::string> columns;            // parameter names, integration constants per record
  std::vector<RecordRows> records;
  std::vector<Region> regions;  // empty when the equations have no guard
  bool weighted = false;        // rows weighted by a record column (eq. 2-1.6)
  LeastSquaresSummary summary;
  // Per row of the design: which equation and record, and at what time (for residual files).
  std::vector<std::size_t> row_equation, row_record;
  std::vector<double> row_time;
  std::vector<double> known;  // the right-hand side per row
};

struct FitSummary {
  std::string model_name;
  std::vector<GroupFit> groups;
  bool is_solution_usable() const;
  std::string brief_report() const;
  std::string full_report(const ir::Model& model) const;
};

std::variant<FitSummary, Diagnostic> fit(const ir::Model& model, const std::vector<SampledRecord>& records,
                                         const FitOptions& options);

// Equations grouped so that two equations sharing a parameter are in one group (in order).
std::vector<std::vector<std::size_t>> equation_groups(const ir::Model& model);

}  // namespace sidc
