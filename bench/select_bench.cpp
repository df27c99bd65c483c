// select_bench: exact best-subset search over 24 candidate operations (2^24 subsets), and that its
// time does not depend on the number of rows n. Not a test: run it by hand (bench/README.md,
// section "select_bench").
//
// Relies on: runtime/solve/triangular_accumulator.hpp (rows -> triangle), runtime/select/best_subset.hpp (the
// search). Guarantees: for each n (default 10^4 and 10^6) and each response, the rows are
// generated here (seeded, so every run sees the same numbers), folded into one triangle (timed:
// this is the only phase that grows with n), and searched (timed: must not grow with n). Three
// responses bracket the search's cost:
//   sparse  - 5 of the 24 columns with noise: the bound cuts most of the tree (typical of a record
//             from a system with few operations);
//   dense   - all 24 columns with coefficients spread over three decades, plus noise;
//   noise   - a response unrelated to the columns: no subset is much better than another, so the
//             bound cuts least (the hard case).
// A fourth line, "no pruning", runs the dense case with tolerance 1e300, which disables every cut:
// all 2^24 subsets are evaluated, the worst case of exact search at p = 24.
// The best subset of size 5 is printed for the sparse case, to show the search is right, not just fast.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <fmt/format.h>

#include "runtime/select/best_subset.hpp"
#include "runtime/solve/triangular_accumulator.hpp"

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

constexpr int kColumns = 24;

// Folds n generated rows into a triangle, 4096 rows at a time (memory does not grow with n).
sidc::TriangularSystem triangle(std::size_t n, const std::string& response, double* seconds) {
  std::mt19937_64 generator(42);
  std::normal_distribution<double> normal;
  sidc::TriangularAccumulator accumulator(kColumns);
  const auto start = Clock::now();
  const std::size_t block = 4096;
  // Noise s.d. grows as sqrt(n / 10^4), so that the coefficients are as well determined at every n
  // and the bound has the same near-ties to sort out: then the subsets evaluated, and the time,
  // should be the same at every n.
  const double noise = std::sqrt(static_cast<double>(n) / 1e4);
  Eigen::MatrixXd A(static_cast<Eigen::Index>(block), kColumns);
  Eigen::VectorXd b(static_cast<Eigen::Index>(block));
  for (std::size_t done = 0; done < n; done += block) {
    const auto m = static_cast<Eigen::Index>(std::min(block, n - done));
    A.resize(m, kColumns);
    b.resize(m);
    for (Eigen::Index i = 0; i < m; ++i) {
      // Correlated columns (a shared factor), as operations of one signal are.
      const double shared = normal(generator);
      for (int j = 0; j < kColumns; ++j) A(i, j) = 0.6 * shared + normal(generator);
      double y = 0;
      if (response == "sparse") y = 2 * A(i, 1) - A(i, 6) + 0.5 * A(i, 11) + 0.8 * A(i, 17) - 0.3 * A(i, 22);
      if (response == "dense")
        for (int j = 0; j < kColumns; ++j) y += std::pow(10.0, -3.0 * j / kColumns) * A(i, j);
      b(i) = y + noise * normal(generator);
    }
    accumulator.add_rows(A, b, nullptr);
  }
  *seconds = since(start);
  return accumulator.system();
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::size_t> sizes{10'000, 1'000'000};
  if (argc > 1) {
    sizes.clear();
    for (int i = 1; i < argc; ++i) sizes.push_back(static_cast<std::size_t>(std::atof(argv[i])));
  }
  fmt::print("exact best-subset search, p = {} candidates (2^{} = {} subsets), keep 1 per size\n", kColumns, kColumns, 1u << kColumns);
  fmt::print("{:>10} {:>11} {:>10} {:>10} {:>12} {:>10}\n", "n", "response", "fold (s)", "search (s)", "subsets", "share");
  for (std::size_t n : sizes) {
    for (const std::string response : {"sparse", "dense", "noise", "no pruning"}) {
      double fold = 0;
      const sidc::TriangularSystem system = triangle(n, response == "no pruning" ? "dense" : response, &fold);
      sidc::BestSubsetOptions options;
      if (response == "no pruning") options.tolerance = 1e300;
      const auto start = Clock::now();
      const sidc::BestSubsetSummary found = sidc::best_subsets(system, options);
      const double search = since(start);
      if (found.termination != sidc::BestSubsetSummary::Termination::success) {
        fmt::print(stderr, "search failed: {}\n", found.message);
        return 1;
      }
      fmt::print("{:>10} {:>11} {:>10.3f} {:>10.3f} {:>12} {:>9.2f}%\n", n, response, fold, search, found.nodes,
                 100.0 * static_cast<double>(found.nodes) / static_cast<double>(found.subsets_total));
      if (response == "sparse") {
        std::string columns;
        for (int c : found.best[5].front().columns) columns += fmt::format(" {}", c);
        fmt::print("{:>10} best subset of size 5:{} (true: 1 6 11 17 22)\n", "", columns);
      }
      std::fflush(stdout);
    }
  }
  return 0;
}
