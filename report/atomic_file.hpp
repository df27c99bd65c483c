// The one way sidc writes a file: whole or not at all, and never over something that is not a file.
//
// A regular destination (or one that does not exist yet) is written to a new, uniquely named
// temporary `DIR/.NAME.XXXXXX` (mkstemp) in the destination's own folder, flushed to disk (fsync),
// then renamed over the destination (rename(2) is atomic within one file system) and the folder
// flushed too, so a reader never sees half a model, half a residual file or half a picture, and a
// failed run leaves the old file as it was. A symbolic link is followed: its target is replaced,
// the link stays. A destination that exists and is not a regular file (a device such as /dev/null,
// a FIFO), or one naming an open descriptor (/dev/stdout, /dev/stderr, /dev/fd/N, /proc/...), is
// written through: opened for appending and written in place, never replaced. A folder is refused.
//
// Every temporary is locked (flock) by the run that made it, for as long as it lives; temporaries
// of this name left by a killed run (unlocked) are removed when the next run writes beside them.
// Folders are locked (flock on the folder) while temporaries are made and while a set is renamed
// in, so concurrent runs into one folder neither remove each other's temporaries nor interleave
// their sets: the files of one run's set are those of the last run to commit.
//
// Relies on: POSIX mkstemp, rename, fsync, flock (Linux: locks on folders are allowed).
// Guarantees: no exception escapes; a failure returns false with a one-line reason in *why
// ("cannot write `FILE`: REASON") and removes the temporaries. Every output of every command goes
// through here (compiled models, fit.json, residuals.csv, validation.csv, select.json, simulated
// records, gnuplot scripts, pictures, reports).
#pragma once

#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace sidc {

// A temporary file beside a destination, locked while this object holds it and removed when it
// is destroyed without having been renamed into place.
class TemporaryFile {
 public:
  TemporaryFile() = default;
  TemporaryFile(std::string path, int descriptor) : path_(std::move(path)), descriptor_(descriptor) {}
  TemporaryFile(TemporaryFile&& other) noexcept;
  TemporaryFile& operator=(TemporaryFile&& other) noexcept;
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  ~TemporaryFile();

  const std::string& path() const { return path_; }
  bool empty() const { return path_.empty(); }
  int descriptor() const { return descriptor_; }
  // Forgets the path once it has been renamed (nothing to remove), and drops the lock.
  void release();
  // Removes the file now.
  void remove();

 private:
  std::string path_;
  int descriptor_ = -1;
};

// Creates an empty, uniquely named file `DIR/.NAME.XXXXXX` beside `destination` (beside the target
// of a symbolic link; mode 0666 less the umask, as a newly created file), after removing the
// leftovers of killed runs for this NAME; an empty TemporaryFile with *why set on failure.
TemporaryFile create_temporary_beside(const std::string& destination, std::string* why);

// Writes `content` into `temporary` (a script handed to another program, still locked).
bool write_temporary(TemporaryFile& temporary, const std::string& content, std::string* why);

// Flushes `temporary` to disk and renames it over `destination` (a written-through destination
// gets its bytes copied instead); on failure the temporary is removed.
bool replace_file(TemporaryFile& temporary, const std::string& destination, std::string* why);

// Writes `content` to `destination` atomically.
bool write_file_atomically(const std::string& destination, const std::string& content, std::string* why);

// The same for contents written piece by piece (a residual file of 10^7 rows is never built as one
// string): `write` streams into the temporary file and returns false to abandon it.
bool write_file_atomically(const std::string& destination, const std::function<bool(std::ostream&)>& write, std::string* why);

// Files that appear together or not at all (a fit's fit.json, residuals.csv, validation.csv): each
// is written into its own temporary by add(), and commit() renames them all in, under the folder's
// lock. Until commit() the previous files stay as they were; a set destroyed without commit()
// removes its temporaries. A written-through destination is written by add() itself.
class AtomicFileSet {
 public:
  bool add(const std::string& destination, const std::function<bool(std::ostream&)>& write, std::string* why);
  bool add(const std::string& destination, const std::string& content, std::string* why);
  // Renames every file in and removes the regular files at `stale` (members of an earlier set that
  // this one does not have, which would otherwise read as part of it).
  bool commit(std::string* why, const std::vector<std::string>& stale = {});

 private:
  struct Staged {
    std::string destination;  // as the caller named it, for messages
    std::string target;       // symbolic links followed
    TemporaryFile temporary;
  };
  std::vector<Staged> staged_;
};

// True when `path` names something sidc writes through rather than replaces (see above).
bool is_written_through(const std::string& path);

// The first of `inputs` that `output` would overwrite (the same regular file, by any path or link),
// or "": a command refuses such an output before it starts (`sidc compile m.sid -o m.sid`).
std::string input_overwritten_by(const std::string& output, const std::vector<std::string>& inputs);

}  // namespace sidc
