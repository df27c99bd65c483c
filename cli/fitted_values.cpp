#include "cli/fitted_values.hpp"

namespace sidc {

std::optional<std::vector<std::pair<std::string, double>>> fitted_values(const nlohmann::json& j) {
  if (j.is_discarded() || !j.is_object() || j.value("format", "") != "sidc-fit" || !j.contains("groups") || !j["groups"].is_array())
    return std::nullopt;
  std::vector<std::pair<std::string, double>> out;
  auto take = [&](const nlohmann::json& parameters, const char* field) {
    if (!parameters.is_array()) return;
    for (const auto& p : parameters)
      if (p.is_object() && p.contains("name") && p["name"].is_string() && p.contains(field) && p[field].is_number())
        out.emplace_back(p["name"].get<std::string>(), p[field].get<double>());
  };
  for (const auto& g : j["groups"])
    if (g.is_object()) take(g.value("parameters", nlohmann::json::array()), "estimate");
  // Nonlinear parameters: the values the equation-error fit held them at.
  const auto& nonlinear = j.contains("nonlinear_parameters") ? j["nonlinear_parameters"] : nlohmann::json();
  if (nonlinear.is_object() && nonlinear.contains("parameters")) take(nonlinear["parameters"], "held");
  const auto& iv = j.contains("instrumental_variables") ? j["instrumental_variables"] : nlohmann::json();
  if (iv.is_object() && iv.value("termination", "") == "converged" && iv.contains("groups") && iv["groups"].is_array())
    for (const auto& g : iv["groups"])
      if (g.is_object()) take(g.value("parameters", nlohmann::json::array()), "estimate");
  const auto& refinement = j.contains("refinement") ? j["refinement"] : nlohmann::json();
  if (refinement.is_object() && refinement.value("status", "") != "failed" && refinement.contains("parameters"))
    take(refinement["parameters"], "refined");
  return out;
}

}  // namespace sidc
