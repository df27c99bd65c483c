// The one translation from a model's typed settings (ir/settings.hpp: `set derivative =
// savgol(7, 3)`, `set edges = shorten`, `set from = 2`, ...) to the runtime's options: how
// operations are evaluated, which rows are fitted, how records are bound. `fit`, `select` and
// `simulate` all go through here, so a setting means the same to every command. Command-line
// options override the settings before the translation (cli/record_options.cpp), never after.
#pragma once

#include "ir/settings.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {

// The derivative (eqs. 3-1.6 to 3-1.8), smoothing and integration (section 3-2) operators.
EvaluationOptions evaluation_options(const EvaluationSettings& settings);

// The evaluation options and the fit window; least-squares options keep their defaults.
FitOptions fit_options(const EvaluationSettings& settings);

// Decimation, the step of a record without a time column, and the weights column (eq. 2-1.6).
BindOptions bind_options(const EvaluationSettings& settings);

}  // namespace sidc
