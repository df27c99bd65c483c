// integrate_pass: equations rewritten into integrated form (thesis sections 2-1, 2-2, 4-1, 4-2).
//
// Relies on: normalize_pass (sum_k a_k op_k = known). Guarantees: each equation is integrated N
// times from the start of the fit window t0 to t, N from its `integrate` setting, the
// `--integrate` option, or `auto` (the smallest N leaving the fewest derivatives to estimate).
// Each integration replaces a term by an exact antiderivative when one is found and checked (its
// symbolic derivative must give back exactly the terms it replaces: y'' -> y', y^2*y' -> y^3/3
// (eq. 2-2.7), y'*y'' -> y'^2/2, x'*y + x*y' -> x*y, constants -> tau, der(u, k) -> der(u, k-1)),
// and otherwise by a
// numerical integral `int(...)`, nested on repeated integration (eq. 2-2.5). A guarded term is
// never integrated symbolically (its antiderivative changes branch), except as der(..., k) by
// definition; with `constants = initial` that happens only where the value at t0 can be written. Integration constants become new parameters C1, C2, ... on
// tau^(N-1)/(N-1)!, ..., tau, 1 (eqs. 2-1.5, 2-2.4, 2-2.5), or, with `constants = initial`, each
// antiderivative has its value at t0 subtracted (eqs. 2-1.4, 4-2.4). Pinned by
// tests/golden/integrated/.
#pragma once

#include <optional>

#include "ir/ir.hpp"
#include "ir/queries.hpp"
#include "diagnostics/diagnostic.hpp"

namespace sidc {

struct IntegrateOptions {
  // Overrides every equation's request when set (the command line's `--integrate N|auto`).
  std::optional<ir::IntegrationRequest> override_request;
};

ir::Model integrate_pass(ir::Model model, const IntegrateOptions& options, Diagnostics& diagnostics);

// The terms of a canonical sum not yet rewritten, in canonical order: each found by its factors
// in O(log n) and taken off without moving the others, so that rewriting a sum of n terms one term
// at a time costs n log n (copying and erasing a vector per term made 10 000 terms take 18 s).
class RemainingTerms {
 public:
  explicit RemainingTerms(const ir::Sum& canonical_sum);
  bool empty() const { return first_ == terms_.size(); }
  const ir::Term& front() const { return terms_[first_]; }
  void pop_front();
  // Where the term with t's factors and coefficient stands, if it is still there.
  std::optional<std::size_t> find(const ir::Term& t) const;
  void take(std::size_t index);

 private:
  std::vector<ir::Term> terms_;
  std::vector<bool> taken_;
  std::size_t first_ = 0;
};

// An exact antiderivative of `t` whose derivative is made of terms all present in `remaining` (t
// among them), which are taken off `remaining`; nullopt, leaving `remaining` as it was, when there
// is none (integrate_pass.cpp: y'' -> y', y^2*y' -> y^3/3, x'*y + x*y' -> x*y, der(u, 1) -> u).
std::optional<ir::Sum> exact_antiderivative(const ir::Term& t, RemainingTerms& remaining, bool initial);

// One integration of a parameter-free sum from t0 to t, constants of integration dropped
// (`initial` = false) or their values at t0 subtracted (`initial` = true).
ir::Sum antiderivative(const ir::Sum& s, bool initial);

}  // namespace sidc
