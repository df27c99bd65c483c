// A lowered sum written as sum_k a_k * op_k + rest (eq. 2-1.2): the terms each parameter
// multiplies, and the terms with no parameter. normalize_pass splits each equation this way, and
// lower_pass each `plot` function.
//
// Relies on: lower_pass's canonical sums, parameters as plain factors, Parameter::nonlinear marked.
// Guarantees: each term holds at most one linear parameter, to the first power, or it is reported
// (`a1*a2*y`, `a1^2`) with its span; nonlinear parameters (`param L = 1.2` inside `sin(L*y)`) stay
// factors of the operations;
// every offending term is reported, not only the first. Numeric factors stay in the operations.
#pragma once

#include <map>
#include <optional>
#include <vector>

#include "ir/ir.hpp"
#include "diagnostics/diagnostic.hpp"

namespace sidc {

struct ParameterSplit {
  std::map<int, std::vector<ir::Term>> operations;  // parameter index -> the terms it multiplies
  std::vector<ir::Term> rest;                        // parameter-free terms, as written
};

std::optional<ParameterSplit> split_by_parameter(const ir::Sum& s, const ir::Model& model, Diagnostics& diagnostics);

}  // namespace sidc
