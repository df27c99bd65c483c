#include "cli/form_options.hpp"

#include "driver/record_settings.hpp"

namespace sidc {

void add_form_options(CLI::App* cmd, FormArguments& a) {
  auto* integrate = cmd->add_option("--integrate", a.integrate, "Integrate every equation N times (0-8), or `auto`; overrides the file");
  cmd->add_option("--form", a.form, "Rewrite every equation into this form: derivative, integrated (as --integrate auto) or weak; overrides the file")
      ->check(CLI::IsMember({"derivative", "integrated", "weak"}))
      ->excludes(integrate);
}

std::optional<ir::IntegrationRequest> integration_request(const FormArguments& a, std::string& error) {
  auto request = driver::integration_request(a.integrate, a.form);
  if (auto* d = std::get_if<Diagnostic>(&request)) {
    error = render(*d);
    return std::nullopt;
  }
  return std::get<std::optional<ir::IntegrationRequest>>(request);
}

}  // namespace sidc
