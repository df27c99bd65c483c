#include "cli/form_options.hpp"

#include <charconv>

#include "diagnostics/model_catalogue.hpp"
#include "ir/settings.hpp"

namespace sidc {

void add_form_options(CLI::App* cmd, FormArguments& a) {
  auto* integrate = cmd->add_option("--integrate", a.integrate, "Integrate every equation N times (0-8), or `auto`; overrides the file");
  cmd->add_option("--form", a.form, "Rewrite every equation into this form: derivative, integrated (as --integrate auto) or weak; overrides the file")
      ->check(CLI::IsMember({"derivative", "integrated", "weak"}))
      ->excludes(integrate);
}

std::optional<ir::IntegrationRequest> integration_request(const FormArguments& a, std::string& error) {
  if (!a.form.empty()) {  // the same request as --integrate, named by its form
    ir::IntegrationRequest r;
    request_form(r, a.form);
    return r;
  }
  if (a.integrate.empty()) return std::nullopt;
  ir::IntegrationRequest r;
  if (a.integrate == "auto") {
    r.count = ir::IntegrationRequest::Count::automatic;
    return r;
  }
  int n = -1;
  const auto [end, ec] = std::from_chars(a.integrate.data(), a.integrate.data() + a.integrate.size(), n);
  if (ec != std::errc() || end != a.integrate.data() + a.integrate.size() || n < 0 || n > 8) {
    error = render(diag::integrate_option_invalid(a.integrate));
    return std::nullopt;
  }
  r.times = n;
  return r;
}

}  // namespace sidc
