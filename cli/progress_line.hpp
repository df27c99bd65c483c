// A progress line on stderr for work that takes a while (issue 16's habit, first for local fits):
// shown only when stderr is a terminal, only once the work has run 2 s, redrawn at most four times
// a second, and ended with a newline when the work is done, so that a piped or logged run sees
// nothing of it.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>

namespace sidc {

class ProgressLine {
 public:
  // Off when stderr is not a terminal.
  ProgressLine();
  ~ProgressLine();  // ends a line left open
  // `phase` has done `done` of `total` units.
  void update(const std::string& phase, std::size_t done, std::size_t total);

 private:
  using Clock = std::chrono::steady_clock;
  bool on_ = false, open_ = false;
  std::string phase_;
  Clock::time_point start_, last_;
};

}  // namespace sidc
