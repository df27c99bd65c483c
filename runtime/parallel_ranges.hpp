// Element-wise work over a whole record on every core: [0, n) cut into one contiguous range per
// thread, each range's elements computed exactly as one thread would (no sum crosses a range), so
// the values are the same bits on any number of cores. Below `serial_below` units of work the call
// runs on the caller's thread alone (a thread costs tens of microseconds to start); when no thread
// can be started, the caller's thread takes the ranges left.
#pragma once

#include <algorithm>
#include <cstddef>
#include <exception>
#include <sched.h>
#include <thread>
#include <vector>

namespace sidc {

// Threads for work split over the cores: one per core this process may run on (its affinity mask:
// `taskset`, or mpirun binding a rank to its cores), at most 8 (the streamed fit's, the local fits'
// and these ranges' default).
inline int core_count() {
  int cores = static_cast<int>(std::thread::hardware_concurrency());
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (sched_getaffinity(0, sizeof allowed, &allowed) == 0) cores = CPU_COUNT(&allowed);
  return std::clamp(cores, 1, 8);
}

// f(first, last) for ranges covering [0, n); `work` is n times the cost of one element, in
// multiply-adds, say.
template <class F>
void for_parallel_ranges(std::size_t n, std::size_t work, F&& f, std::size_t serial_below = std::size_t{1} << 22) {
  const std::size_t threads = work < serial_below || n < 2 ? 1 : std::min<std::size_t>(n, static_cast<std::size_t>(core_count()));
  if (threads == 1) {
    f(std::size_t{0}, n);
    return;
  }
  auto range = [&f, n, threads](std::size_t t) { f(n * t / threads, n * (t + 1) / threads); };
  std::vector<std::thread> running;
  try {
    running.reserve(threads - 1);
    for (std::size_t t = 1; t < threads; ++t) running.emplace_back(range, t);
  } catch (const std::exception&) {  // no thread (or no memory) to be had: the ranges not started run here
  }
  range(0);
  for (std::size_t t = running.size() + 1; t < threads; ++t) range(t);
  for (auto& t : running) t.join();
}

}  // namespace sidc
