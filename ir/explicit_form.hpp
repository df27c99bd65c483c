// The explicit form of a model: its equations solved for each output's highest derivative, the
// shape an ODE solver needs (thesis section 2-4: "solving the system equation" with the
// determined parameters, eq. 4-1.1 solved for y''). The types only: compiler/explicit_form_pass
// builds it from the normalized model, the compiled model carries it, and runtime/simulate/
// solves it.
//
// For outputs y_1..y_k of orders n_1..n_k, each equation i reads
//     sum_j A_ij * y_j^(n_j) + r_i = 0,
// where A_ij and r_i are linear in the parameters (one Sum per parameter plus a parameter-free
// Sum) and contain no highest derivative; the runtime substitutes parameter values and solves the
// k x k linear system at each instant (k = 1: y^(n) = -r / A).
#pragma once

#include <string>
#include <vector>

#include "ir/ir.hpp"

namespace sidc {

// A Sum linear in the parameters: constant + sum_k a_k * terms[k].operation.
struct ParametricSum {
  std::vector<ir::ParameterTerm> terms;  // parameter indices into the normalized Model::parameters
  ir::Sum constant;
  bool empty() const { return terms.empty() && constant.empty(); }
};

struct ExplicitForm {
  struct Output {
    std::string name;
    int order = 0;  // n: the state holds y, y', ..., y^(n-1); the equations give y^(n)
    Span span;
  };
  std::vector<Output> outputs;
  // Equation i: sum_j coefficient[i][j] * outputs[j]^(order_j) + rest[i] = 0.
  std::vector<std::vector<ParametricSum>> coefficient;
  std::vector<ParametricSum> rest;
  std::vector<Span> equation_spans;
  // A matching of equations to outputs (equation i is "the equation of" outputs[matched[i]]),
  // for messages; the runtime solves the whole linear system, so the choice does not matter.
  std::vector<int> matched;
  // Every guard condition in the equations as `lhs - rhs`, and every argument of sign(): where one
  // changes sign a branch switches (eq. 4-1.2's damper, Coulomb friction's sign(y')), and a
  // fixed-step solver locates that time.
  std::vector<ir::Sum> switching_functions;
  std::size_t state_size() const;
};

}  // namespace sidc
