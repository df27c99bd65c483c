#include "ir/settings.hpp"

#include <charconv>
#include <cmath>
#include <regex>

#include "ir/units.hpp"

namespace sidc {
namespace {

std::optional<double> positive_number(const std::string& text, bool allow_zero = false) {
  const auto n = Number::parse(text);
  if (!n) return std::nullopt;
  const double v = n->value();
  if (!(v > 0 || (allow_zero && v == 0)) || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::optional<int> whole_number(const std::string& text) {
  int v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return v;
}

}  // namespace

const std::vector<std::string>& setting_keys() {
  static const std::vector<std::string> keys{"integrate", "form", "constants", "derivative", "second_derivative", "edges",
                                             "integration", "smooth_before_integration", "from", "to", "every", "step", "weights", "refine",
                                             "estimator", "time_unit", "local", "weak_weighting"};
  return keys;
}

std::optional<MovingArc> parse_moving_arc(const std::string& text) {
  static const std::regex form(R"(savgol\s*\(\s*(\d{1,4})\s*,\s*(\d{1,3})\s*\))");
  static const std::regex automatic(R"(savgol\s*\(\s*auto\s*\))");
  if (std::regex_match(text, automatic)) return MovingArc{7, 3, true};
  std::smatch m;
  if (!std::regex_match(text, m, form)) return std::nullopt;
  MovingArc arc{std::stoi(m[1]), std::stoi(m[2])};
  if (arc.window < 3 || arc.window % 2 == 0 || arc.order < 1 || arc.order >= arc.window) return std::nullopt;
  return arc;
}

SettingCheck check_setting(const std::string& key, const std::string& value) {
  SettingCheck r;
  if (key == "integrate") {
    const auto n = whole_number(value);
    if (value != "auto" && (!n || *n < 0 || *n > kMaxIntegrations))
      r.expected = "a whole number of integrations from 0 to 8, or `auto`";
  } else if (key == "form") {
    if (value != "derivative" && value != "integrated" && value != "weak")
      r.expected = "`derivative` (no integration), `integrated` (as `integrate = auto`) or `weak` (integrated against test "
                   "functions on subdomains: no derivative of the data, no integration constant)";
  } else if (key == "constants") {
    if (value != "fitted" && value != "initial")
      r.expected = "`fitted` (integration constants become parameters, eq. 2-1.5) or `initial` (taken from the record, eq. 4-2.4)";
  } else if (key == "derivative" || key == "smooth_before_integration") {
    const auto arc = parse_moving_arc(value);
    const bool fits = key == "derivative" ? arc.has_value() : (arc && !arc->automatic) || value == "off";
    if (!fits)
      r.expected = std::string("`savgol(window, order)` with an odd window of at least 3 and an order from 1 to window - 1, "
                               "e.g. `savgol(7, 3)` (thesis eq. 3-1.7)") +
                   (key == "derivative" ? ", or `savgol(auto)` (chosen from the record, the default)" : ", or `off`");
  } else if (key == "second_derivative") {
    if (value != "repeated" && value != "direct")
      r.expected = "`repeated` (the first-derivative operator applied twice, eq. 3-1.8) or `direct`";
  } else if (key == "edges") {
    if (value != "drop" && value != "shorten")
      r.expected = "`drop` (points without a full neighbourhood are not used, as the thesis) or `shorten`";
  } else if (key == "integration") {
    if (value != "simpson" && value != "trapezoid") r.expected = "`simpson` or `trapezoid`";
  } else if (key == "from" || key == "to") {
    if (!positive_number(value, true) && !(Number::parse(value) && std::isfinite(Number::parse(value)->value())))
      r.expected = "a time, e.g. `0.82`";
  } else if (key == "every") {
    const auto n = whole_number(value);
    if (!n || *n < 1) r.expected = "a whole number of at least 1 (keep every k-th sample)";
  } else if (key == "weights") {
    static const std::regex column(R"("[^"]+"|[A-Za-z_][A-Za-z0-9_]*)");
    if (!std::regex_match(value, column)) r.expected = "the name of a record column holding the weight of each row (eq. 2-1.6), e.g. `w` or `\"weight\"`";
  } else if (key == "refine") {
    if (value != "none" && value != "simulation")
      r.expected = "`simulation` (refine the fit by the error of the solved equations, `sidc fit --refine`) or `none`";
  } else if (key == "estimator") {
    if (value != "least_squares" && value != "iv")
      r.expected = "`least_squares` (equation error, thesis section 2-1; the default) or `iv` (refined instrumental variables: "
                   "instruments from the fitted equations solved without noise)";
  } else if (key == "weak_weighting") {
    if (value != "covariance" && value != "none")
      r.expected = "`covariance` (the weak form's rows weighted by the covariance their noise gives them: generalised least "
                   "squares, the default) or `none` (least squares of rows taken as independent)";
  } else if (key == "time_unit") {
    ir::UnitParseError error;
    if (!ir::parse_unit(value, &error))
      r.expected = "a unit of time such as `s`, `min` or `ms` (" + error.message + " at character " +
                   std::to_string(error.offset + 1) + ")";
  } else if (key == "local") {
    if (!positive_number(value)) r.expected = "the width of the local fits' window, in time, e.g. `2.5` (sidc fit --local, thesis chapter V)";
  } else if (key == "step") {
    if (!positive_number(value)) r.expected = "a positive sampling step, e.g. `0.01`";
  } else {
    r.unknown_key = true;
  }
  return r;
}

bool refine_by_simulation(const ir::Settings& settings) {
  auto it = settings.values.find("refine");
  return it != settings.values.end() && it->second.text == "simulation";
}

void request_form(ir::IntegrationRequest& request, const std::string& form) {
  request.weak = form == "weak";
  request.count = form == "integrated" ? ir::IntegrationRequest::Count::automatic : ir::IntegrationRequest::Count::fixed;
  request.times = 0;
}

std::optional<double> local_width_setting(const ir::Settings& settings) {
  auto it = settings.values.find("local");
  if (it == settings.values.end()) return std::nullopt;
  return Number::parse(it->second.text)->value();
}

Estimator estimator_setting(const ir::Settings& settings) {
  auto it = settings.values.find("estimator");
  return it != settings.values.end() && it->second.text == "iv" ? Estimator::instrumental_variables : Estimator::least_squares;
}

EvaluationSettings evaluation_settings(const ir::Settings& settings) {
  EvaluationSettings e;
  auto get = [&](const char* key) -> const std::string* {
    auto it = settings.values.find(key);
    return it == settings.values.end() ? nullptr : &it->second.text;
  };
  if (auto v = get("derivative")) e.derivative = *parse_moving_arc(*v);
  if (auto v = get("second_derivative")) e.second_derivative_repeated = *v == "repeated", e.second_derivative_given = true;
  if (auto v = get("edges")) e.shorten_edges = *v == "shorten";
  if (auto v = get("integration")) e.trapezoid = *v == "trapezoid";
  if (auto v = get("smooth_before_integration"); v && *v != "off") e.smooth_before_integration = parse_moving_arc(*v);
  if (auto v = get("from")) e.from = Number::parse(*v)->value();
  if (auto v = get("to")) e.to = Number::parse(*v)->value();
  if (auto v = get("every")) e.every = std::stoi(*v);
  if (auto v = get("step")) e.step = Number::parse(*v)->value();
  if (auto v = get("weights")) e.weights = v->front() == '"' ? v->substr(1, v->size() - 2) : *v;
  if (auto v = get("weak_weighting")) e.weak_covariance = *v == "covariance";
  return e;
}

}  // namespace sidc
