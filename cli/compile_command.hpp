// `sidc compile MODEL`: the model file checked and rewritten, its integrated form printed and the
// compiled model written for `sidc fit` (docs/cli.md).
#pragma once

#include <CLI/CLI.hpp>

namespace sidc {

void add_compile_command(CLI::App& app, int& exit_status);

}  // namespace sidc
