// The model a command works on, from the path the user gave: a model file (`.sid`) compiled in
// memory with default options (nothing written), or a compiled model file (`.sidc.json`) read
// back. Either way the result carries its explicit form (pipeline.hpp), so `fit`, `select` and
// `simulate` load a model the same way and none derives anything again.
//
// Relies on: pipeline.hpp (compile, compiled_model, read_compiled_model). Guarantees: nullopt with
// `error` (rendered diagnostics, no trailing newline) when the file cannot be read, does not
// compile, or is no valid compiled model; `warnings` (rendered, each ending in a newline) holds
// what the user should still hear: compiler warnings, and a model file changed since it was compiled.
#pragma once

#include <optional>
#include <string>

#include "ir/compiled_model.hpp"

namespace sidc {

std::optional<CompiledModel> load_compiled_model(const std::string& path, std::string& error, std::string& warnings);

}  // namespace sidc
