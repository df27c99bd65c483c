// Parts of a shared computation (runtime/records/part_share.hpp, runtime/solve/row_share.hpp) as
// threads of one test process: they meet in a ThreadRoom and merge, sum and concatenate through
// memory, which is what distributed/'s MPI share does between processes (tests/distributed/ runs
// that one under mpirun). in_parts() runs a function on every part side by side.
#pragma once

#include <algorithm>
#include <barrier>
#include <span>
#include <thread>
#include <utility>
#include <vector>

#include "runtime/solve/row_share.hpp"

namespace sidc {

// The parts' meeting room: each part leaves its state, all wait, each merges all states in part
// order (so every part computes the same bits), all wait again before the room is reused.
struct ThreadRoom {
  explicit ThreadRoom(int n) : parts(n), barrier(n), states(static_cast<std::size_t>(n)), values(static_cast<std::size_t>(n)),
                               problems(static_cast<std::size_t>(n)) {}
  int parts;
  std::barrier<> barrier;
  std::vector<std::vector<double>> states, values;
  std::vector<char> problems;
  int problem_rounds = 0;  // combines that found a problem in some part's rows (counted by part 0)
  int sums = 0;            // sum() calls (counted by part 0)
};

class ThreadShare final : public RowShare {
 public:
  ThreadShare(ThreadRoom& room, int part) : room_(room), part_(part) {}
  int part() const override { return part_; }
  int parts() const override { return room_.parts; }
  // Merged left to right in part order (MPI's share merges by a tree: the same to rounding).
  Combined merge(std::vector<double>& state, const Merge& merge_two, bool has_problem) override {
    const auto me = static_cast<std::size_t>(part_);
    room_.states[me] = state;
    room_.problems[me] = has_problem ? 1 : 0;
    room_.barrier.arrive_and_wait();
    Combined result;
    if (std::any_of(room_.problems.begin(), room_.problems.end(), [](char p) { return p != 0; })) {
      result.outcome = Outcome::problem;
      if (part_ == 0) ++room_.problem_rounds;
    } else {
      std::vector<double> merged = room_.states[0];
      for (std::size_t k = 1; k < room_.states.size(); ++k) merge_two(merged, room_.states[k]);
      state = merged;
    }
    room_.barrier.arrive_and_wait();
    return result;
  }

  void concatenate(std::span<const double> mine, std::span<double> all, std::span<const std::size_t> lengths) override {
    const auto me = static_cast<std::size_t>(part_);
    room_.values[me].assign(mine.begin(), mine.end());
    room_.barrier.arrive_and_wait();
    std::size_t offset = 0;
    for (std::size_t k = 0; k < room_.values.size(); ++k) {
      std::copy(room_.values[k].begin(), room_.values[k].end(), all.begin() + static_cast<std::ptrdiff_t>(offset));
      offset += lengths[k];
    }
    room_.barrier.arrive_and_wait();
  }

  Combined sum(std::span<double> values, bool has_problem) override {
    const auto me = static_cast<std::size_t>(part_);
    room_.values[me].assign(values.begin(), values.end());
    room_.problems[me] = has_problem ? 1 : 0;
    room_.barrier.arrive_and_wait();
    Combined result;
    if (part_ == 0) ++room_.sums;
    if (std::any_of(room_.problems.begin(), room_.problems.end(), [](char p) { return p != 0; })) {
      result.outcome = Outcome::problem;
    } else {
      for (std::size_t j = 0; j < values.size(); ++j) {
        double total = 0;
        for (const auto& v : room_.values) total += v[j];
        values[j] = total;
      }
    }
    room_.barrier.arrive_and_wait();
    return result;
  }

 private:
  ThreadRoom& room_;
  int part_;
};

// run(share, k) for every part k of the room, the parts side by side as threads; their results.
template <class Run>
inline auto in_parts(ThreadRoom& room, Run run) {
  using Result = decltype(run(std::declval<RowShare&>(), 0));
  std::vector<ThreadShare> shares;
  for (int k = 0; k < room.parts; ++k) shares.emplace_back(room, k);
  std::vector<Result> results(static_cast<std::size_t>(room.parts));
  std::vector<std::thread> threads;
  for (int k = 0; k < room.parts; ++k)
    threads.emplace_back([&, k] { results[static_cast<std::size_t>(k)] = run(shares[static_cast<std::size_t>(k)], k); });
  for (auto& t : threads) t.join();
  return results;
}

}  // namespace sidc
