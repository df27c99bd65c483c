// Several models fitted to the same records, compared (thesis section 2-1: "if the system equation
// has several alternate forms, that form which possesses a minimum sum of the squares of the
// residuals will constitute the solution of best fit"; Table 4-1.2).
//
// G(a) only compares forms fitted to the same rows with the same known side: the residuals of
// `= x` and of `= int(x)` are in different units. AIC and BIC also weigh the number of parameters
// (n log(G/n) + 2p and n log(G/n) + p log n), and need the same known side but not the same rows.
// Guarantees: a rank-deficient fit is listed and never marked best.
#pragma once

#include <string>
#include <vector>

#include "ir/ir.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {

// One model's fit, summed over its equation groups.
struct ModelTotals {
  std::string name;
  std::string known;  // the known sides, printed: G(a) compares only models that share them
  std::size_t n = 0, p = 0;
  double G = 0;
  bool usable = false;
  double aic = 0, bic = 0;  // filled by compare_models
  bool least_G = false, best_aic = false, best_bic = false;
};

// `name` is shown in the table (the model's name, or its file when it has none).
ModelTotals model_totals(const std::string& name, const ir::Model& model, const FitSummary& summary);

struct ModelComparison {
  std::vector<ModelTotals> models;  // as given, with criteria and marks
  bool same_rows = true, same_known = true;
};

ModelComparison compare_models(std::vector<ModelTotals> models);

}  // namespace sidc
