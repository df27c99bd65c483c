// `sidc fit [COMPILED...]`: parameters from records, with the statistics to trust them (docs/cli.md).
#pragma once

#include <CLI/CLI.hpp>

namespace sidc {

void add_fit_command(CLI::App& app, int& exit_status);

}  // namespace sidc
