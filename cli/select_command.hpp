// `sidc select`: determination of operations (thesis section 2-3, issue 6). Parses the command
// line, loads the model and records as `sidc fit` does, runs runtime/select/select.hpp and prints a
// Table 4-1.2-style table; `--out DIR` also writes DIR/select.json.
#pragma once

#include <CLI/CLI.hpp>

namespace sidc {

void add_select_command(CLI::App& app, int& exit_status);

}  // namespace sidc
