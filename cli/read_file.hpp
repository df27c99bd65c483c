// Reading a whole input file (a model, a compiled model, a fit's parameters), with the user-facing
// error when it cannot be read. Every file sidc writes goes through report/atomic_file.hpp.
#pragma once

#include <optional>
#include <string>

namespace sidc {

// The file's bytes, or nullopt with `error` set to a one-line reason naming the file.
std::optional<std::string> read_whole_file(const std::string& path, std::string& error);

}  // namespace sidc
