// `sidc fit [COMPILED...]`: parameters from records, with the statistics to trust them (docs/cli.md).
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "ir/compiled_model.hpp"

namespace sidc {

void add_fit_command(CLI::App& app, int& exit_status);

// A compiled model (.sidc.json), or a model file (.sid) compiled in memory (warnings go to
// stderr); nullopt with `error` holding the rendered message. Shared with `sidc simulate`.
std::optional<CompiledModel> load_compiled_model(const std::string& path, std::string& error);

}  // namespace sidc
