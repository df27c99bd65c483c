// Reading a whole input file, with the user-facing error when it cannot be read.
#pragma once

#include <functional>
#include <optional>
#include <ostream>
#include <string>

namespace sidc {

// The file's bytes, or nullopt with `error` set to a one-line reason naming the file.
std::optional<std::string> read_whole_file(const std::string& path, std::string& error);

// Writes `contents` to `path` atomically (a temporary file beside it, then rename), so that a
// failure never leaves a half-written file. False with `error` set on failure.
bool write_file_atomically(const std::string& path, const std::string& contents, std::string& error);

// The same for contents written piece by piece (a residual file of 10^7 rows is not built as one
// string): `write` streams into the temporary file and returns false to abandon it.
bool write_file_atomically(const std::string& path, const std::function<bool(std::ostream&)>& write, std::string& error);

}  // namespace sidc
