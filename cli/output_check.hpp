// Outputs named on the command line, checked before any work is done: a fit of a long record
// should not run for minutes and then fail on a mistyped `--out`.
//
// Relies on: POSIX access(2) for write permission. Guarantees: nothing is created or changed on
// disk; a problem comes back as a rendered `output-not-writable` diagnostic naming the option.
// The check can pass and the write still fail (a full disk, a folder removed meanwhile): the
// writers keep reporting their own errors.
#pragma once

#include <optional>
#include <string>

namespace sidc {

enum class OutputKind { file, directory };

// nullopt when `path` (empty: not asked for) can be written as `kind`: the path is absent or of
// that kind, and the nearest folder that exists on the way to it is writable. Else the message.
std::optional<std::string> output_problem(const std::string& option, const std::string& path, OutputKind kind);

}  // namespace sidc
