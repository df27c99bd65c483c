#include "cli/progress_line.hpp"

#include <cstdio>
#include <fmt/format.h>
#include <unistd.h>

namespace sidc {

ProgressLine::ProgressLine() : on_(::isatty(STDERR_FILENO) == 1) {}

ProgressLine::~ProgressLine() {
  if (open_) std::fputs("\n", stderr);
}

void ProgressLine::update(const std::string& phase, std::size_t done, std::size_t total) {
  if (!on_) return;
  const auto now = Clock::now();
  if (phase != phase_) {
    if (open_) std::fputs("\n", stderr);
    open_ = false;
    phase_ = phase;
    start_ = now;
    last_ = now - std::chrono::seconds(1);
  }
  const double seconds = std::chrono::duration<double>(now - start_).count();
  const bool finished = done >= total;
  if ((seconds < 2 && !open_) || (!finished && now - last_ < std::chrono::milliseconds(250))) return;
  last_ = now;
  const double rate = seconds > 0 ? static_cast<double>(done) / seconds : 0;
  std::fputs(fmt::format("\rsidc: {}: {} of {} ({:.0f}%), {:.0f}/s, {:.1f} s ", phase, done, total,
                         total ? 100.0 * static_cast<double>(done) / static_cast<double>(total) : 100.0, rate, seconds)
                 .c_str(),
             stderr);
  open_ = true;
  if (finished) {
    std::fputs("\n", stderr);
    open_ = false;
  }
  std::fflush(stderr);
}

}  // namespace sidc
