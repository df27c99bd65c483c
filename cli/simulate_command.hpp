// `sidc simulate MODEL`: the model's equations solved with given parameter values (docs/cli.md).
#pragma once

#include <CLI/CLI.hpp>

namespace sidc {

void add_simulate_command(CLI::App& app, int& exit_status);

}  // namespace sidc
