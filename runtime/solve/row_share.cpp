// runtime/solve/row_share.hpp: the streamed fit's merge on top of RowShare::merge.
#include "runtime/solve/row_share.hpp"

namespace sidc {

// The state: the number of counts, the counts, then the factor's own state (to_doubles).
RowShare::Combined RowShare::combine(TriangularAccumulator& accumulator, std::vector<double>& counts, bool has_problem) {
  std::vector<double> state{static_cast<double>(counts.size())};
  state.insert(state.end(), counts.begin(), counts.end());
  const std::vector<double> factor = accumulator.to_doubles();
  state.insert(state.end(), factor.begin(), factor.end());
  const int p = accumulator.columns();
  const auto unpack = [](const std::vector<double>& s, std::vector<double>& sums, TriangularAccumulator& into) {
    const auto k = static_cast<std::ptrdiff_t>(s.at(0));
    sums.assign(s.begin() + 1, s.begin() + 1 + k);
    into.from_doubles(std::vector<double>(s.begin() + 1 + k, s.end()));
  };
  const Merge merge_two = [&](std::vector<double>& left, const std::vector<double>& right) {
    std::vector<double> left_counts, right_counts;
    TriangularAccumulator a(p), b(p);
    unpack(left, left_counts, a);
    unpack(right, right_counts, b);
    a.merge(b);
    for (std::size_t j = 0; j < left_counts.size() && j < right_counts.size(); ++j) left_counts[j] += right_counts[j];
    left.assign(1, static_cast<double>(left_counts.size()));
    left.insert(left.end(), left_counts.begin(), left_counts.end());
    const std::vector<double> merged = a.to_doubles();
    left.insert(left.end(), merged.begin(), merged.end());
  };
  const Combined result = merge(state, merge_two, has_problem);
  if (result.outcome == Outcome::combined) unpack(state, counts, accumulator);
  return result;
}

}  // namespace sidc
