// `sidc export FIT.json --as c|python|latex`: the fitted equations with their numbers, as code to
// integrate outside sidc or as LaTeX for a paper (report/model_export.hpp writes them).
#pragma once

#include <CLI/CLI.hpp>

namespace sidc {

void add_export_command(CLI::App& app, int& exit_status);

}  // namespace sidc
