// Files that appear whole or not at all: written under a temporary name in the destination's own
// directory, then renamed over the destination (rename(2) is atomic within one file system), so a
// reader never sees half a picture or half a report, and a failed run leaves the old file intact.
//
// Relies on: POSIX mkstemp and rename. Guarantees: no exception escapes; a failure returns false
// with the reason in *why and removes the temporary file.
#pragma once

#include <string>

namespace sidc {

// Creates an empty, uniquely named file `DIR/.STEM.XXXXXX` beside `destination` and returns its
// path, or "" with *why set.
std::string create_temporary_beside(const std::string& destination, std::string* why);

// Renames `temporary` over `destination`; on failure removes `temporary`.
bool replace_file(const std::string& temporary, const std::string& destination, std::string* why);

// Writes `content` to `destination` atomically (temporary file, flush, rename).
bool write_file_atomically(const std::string& destination, const std::string& content, std::string* why);

}  // namespace sidc
