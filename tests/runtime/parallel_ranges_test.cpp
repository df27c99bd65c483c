// runtime/parallel_ranges.hpp: the ranges cover [0, n) once each, in contiguous pieces, serially
// below the work threshold and on several threads above it.
#include <atomic>
#include <mutex>
#include <set>
#include <thread>
#include <vector>
#include <gtest/gtest.h>

#include "runtime/parallel_ranges.hpp"

namespace sidc {
namespace {

TEST(ParallelRanges, CoverEveryElementOnceSeriallyOrNot) {
  for (std::size_t n : {0u, 1u, 2u, 7u, 1000u, 100003u}) {
    for (std::size_t work : {std::size_t{0}, std::size_t{1} << 30}) {
      std::vector<std::atomic<int>> seen(n);
      std::mutex lock;
      std::set<std::thread::id> threads;
      std::size_t calls = 0;
      for_parallel_ranges(n, work, [&](std::size_t first, std::size_t last) {
        ASSERT_LE(first, last);
        ASSERT_LE(last, n);
        for (std::size_t i = first; i < last; ++i) ++seen[i];
        const std::lock_guard<std::mutex> hold(lock);
        threads.insert(std::this_thread::get_id());
        ++calls;
      });
      for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(seen[i].load(), 1) << "n " << n << ", element " << i;
      if (work == 0 || n < 2) {
        EXPECT_EQ(calls, 1u);  // below the threshold: one call on the caller's thread
        EXPECT_EQ(threads.count(std::this_thread::get_id()), 1u);
      } else {
        EXPECT_EQ(calls, std::min<std::size_t>(n, static_cast<std::size_t>(core_count())));
      }
    }
  }
}

}  // namespace
}  // namespace sidc
