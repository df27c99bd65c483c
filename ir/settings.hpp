// The settings a model file can carry (`set key = value`), their allowed values, and their typed
// form. The compiler checks and types them here so that the runtime never reads setting text.
// docs/language.md ("Settings") lists them; command-line options of `sidc fit` override them.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ir/ir.hpp"

namespace sidc {

inline constexpr int kMaxFamilySize = 10000;  // members of one `param c[a..b]` or one `sum`
inline constexpr int kMaxIntegrations = 8;
// The highest derivative order a model may ask for, counting primes and der() orders together
// (`der(y'', 3)` is of order 5). The compiled-model reader refuses higher ones, and no record gives
// derivatives that high: the moving arc of order k needs a polynomial of degree k or more.
inline constexpr int kMaxDerivativeOrder = 64;
// The largest magnitude of an exponent on anything but a number (`y^10000`): beyond it every
// value of a signal other than 0 and 1 overflows or vanishes, and expanding it costs as many steps.
inline constexpr long long kMaxExponent = 10'000;

struct SettingCheck {
  bool unknown_key = false;
  std::string expected;  // non-empty when the value is invalid: what the key takes
};
SettingCheck check_setting(const std::string& key, const std::string& value);
const std::vector<std::string>& setting_keys();

// A moving-arc (Savitzky-Golay) operator: polynomial of `order` fitted to `window` points, or
// `savgol(auto)`: window and order chosen per signal and derivative order from the record
// (runtime/operators/operator_choice.hpp; the compiler only records the wish).
struct MovingArc {
  int window = 7;  // the thesis' 7-point cubic, eqs. 3-1.6 to 3-1.8
  int order = 3;
  bool automatic = false;
};

struct EvaluationSettings {
  MovingArc derivative{7, 3, true};        // `derivative` unset: savgol(auto)
  bool second_derivative_repeated = true;  // eq. 3-1.8: the first-derivative operator applied twice
  bool second_derivative_given = false;    // written: savgol(auto) keeps to that way
  bool shorten_edges = false;              // thesis: drop points without a full neighbourhood
  bool trapezoid = false;                  // integration rule; Simpson by default (section 3-2)
  std::optional<MovingArc> smooth_before_integration;
  std::optional<double> from, to;          // fit window in time
  int every = 1;                           // decimation
  std::optional<double> step;              // sampling step when the record has no time column
  std::optional<std::string> weights;      // a record column weighting each row's residual (eq. 2-1.6)
  bool weak_covariance = true;             // `weak_weighting = covariance`: the weak rows whitened by their noise
};

// `form` (`derivative`, `integrated`, `weak`; check_setting has accepted it) as the integration
// request it names: `integrate = 0`, `integrate = auto`, or the weak form. The request's constants
// and span are left as they are. Shared by `set form`, `sidc compile --form` and sidc fit's choice.
void request_form(ir::IntegrationRequest& request, const std::string& form);

// `set refine = simulation`: sidc fit refines the equation-error estimate by the output error
// (runtime/refine/refine.hpp), as `--refine` asks.
bool refine_by_simulation(const ir::Settings& settings);

// Typed settings from checked raw values (check_setting has accepted every one).
EvaluationSettings evaluation_settings(const ir::Settings& settings);

// `set estimator`: the equation-error least squares of thesis section 2-1 (`least_squares`, the
// default), or that fit refined by instrumental variables (`iv`, runtime/solve/instrumental_variables.hpp).
enum class Estimator { least_squares, instrumental_variables };
Estimator estimator_setting(const ir::Settings& settings);

// `set local = WIDTH`: sidc fit also fits the model on every window of that width along the
// records (runtime/solve/local_fit.hpp), as `--local WIDTH` asks.
std::optional<double> local_width_setting(const ir::Settings& settings);

// Reads `savgol(7, 3)` or `savgol(auto)`; nullopt if the text is not of that form with a valid
// window and order.
std::optional<MovingArc> parse_moving_arc(const std::string& text);

}  // namespace sidc
