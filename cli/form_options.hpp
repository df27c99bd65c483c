// `--integrate N|auto` and `--form derivative|integrated|weak`, shared by `sidc compile` and
// `sidc fit`: the same request as the model's `set integrate`/`set form` (docs/language.md),
// overriding every equation's.
//
// Relies on: driver/record_settings.hpp (integration_request, shared with the Python module).
// Guarantees: the two options exclude each other and read the same way in both commands; a bad
// `--integrate` value is a rendered usage error, never an exception.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "ir/ir.hpp"

namespace sidc {

struct FormArguments {
  std::string integrate;  // "", "auto" or 0..8
  std::string form;       // "", "derivative", "integrated" or "weak" (CLI11 checks the value)
};

void add_form_options(CLI::App* command, FormArguments& arguments);

// The request the options make; nullopt when neither is given, or (with `error` set) when
// `--integrate` is not 0-8 or `auto`.
std::optional<ir::IntegrationRequest> integration_request(const FormArguments& arguments, std::string& error);

}  // namespace sidc
