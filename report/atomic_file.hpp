// The one way sidc writes a file: whole or not at all. The contents go to a new, uniquely named
// temporary file in the destination's own directory, which is then renamed over the destination
// (rename(2) is atomic within one file system), so a reader never sees half a model, half a
// residual file or half a picture, and a failed run leaves the old file intact.
//
// Relies on: POSIX mkstemp and rename. Guarantees: no exception escapes; a failure returns false
// with a one-line reason in *why ("cannot write `FILE`: REASON") and removes the temporary file.
// Every output of every command goes through here (compiled models, fit.json, residuals.csv,
// validation.csv, select.json, simulated records, gnuplot scripts, pictures, reports).
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace sidc {

// Creates an empty, uniquely named file `DIR/.STEM.XXXXXX` beside `destination` (mode 0666 less
// the umask, as a newly created file) and returns its path, or "" with *why set.
std::string create_temporary_beside(const std::string& destination, std::string* why);

// Renames `temporary` over `destination`; on failure removes `temporary`.
bool replace_file(const std::string& temporary, const std::string& destination, std::string* why);

// Writes `content` to `destination` atomically (temporary file, flush, rename).
bool write_file_atomically(const std::string& destination, const std::string& content, std::string* why);

// The same for contents written piece by piece (a residual file of 10^7 rows is never built as one
// string): `write` streams into the temporary file and returns false to abandon it.
bool write_file_atomically(const std::string& destination, const std::function<bool(std::ostream&)>& write, std::string* why);

}  // namespace sidc
