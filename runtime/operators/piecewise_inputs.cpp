#include "runtime/operators/piecewise_inputs.hpp"

#include <algorithm>
#include <cmath>

#include "ir/traversal.hpp"

namespace sidc {

const ir::Signal* piecewise_input_of(const ir::Model& model, const ir::Term& t) {
  return first_piecewise_input(model, ir::canonical(std::vector<ir::Term>{t}));
}

bool has_piecewise_integral(const ir::Model& model, const ir::Term& t) {
  return ir::any_factor(ir::canonical(std::vector<ir::Term>{t}),
                        [&](const ir::Factor& f) { return f.kind == ir::FactorKind::integral && first_piecewise_input(model, *f.argument); });
}

bool has_piecewise_inputs(const ir::Model& model) {
  return std::any_of(model.signals.begin(), model.signals.end(), [&](const ir::Signal& s) { return piecewise_input(model, s.name) != nullptr; });
}

std::vector<unsigned char> piece_boundaries(const SampledRecord& record, const ir::Model& model) {
  std::vector<unsigned char> boundary(record.time.size(), 0);
  for (const auto& [name, x] : record.signals) {
    const ir::Signal* input = piecewise_input(model, name);
    if (!input) continue;
    for (std::size_t k = 1; k < x.size(); ++k) {
      const bool changes = input->hold == ir::Signal::Hold::held ? x[k] != x[k - 1]
                                                                 : k + 1 < x.size() && x[k + 1] - x[k] != x[k] - x[k - 1];
      if (changes) boundary[k] = 1;
    }
  }
  return boundary;
}

SampledRecord piece_record(const SampledRecord& record, const ir::Model& model, int d) {
  SampledRecord out = record;
  for (auto& [name, values] : out.signals) {
    const ir::Signal* input = piecewise_input(model, name);
    if (!input) continue;
    const Column& x = record.signals.at(name);
    std::vector<double>& shifted = values.owned();
    const auto n = static_cast<std::ptrdiff_t>(x.size());
    if (n == 0) continue;
    auto at = [&](std::ptrdiff_t k) { return x[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(k, 0, n - 1))]; };
    for (std::ptrdiff_t k = 0; k < n; ++k) {
      const std::ptrdiff_t i = k - d;  // the interval whose piece sample k is read from
      shifted[static_cast<std::size_t>(k)] = input->hold == ir::Signal::Hold::held ? at(i) : at(i) + d * (at(i + 1) - at(i));
    }
  }
  return out;
}

std::array<double, 4> interval_rule(int lo, int hi, int m) {
  // Gauss-Legendre on [0, 1], 6 points: exact to degree 11, here at most 3 + m.
  static constexpr double node[6] = {0.033765242898423987, 0.16939530676686776, 0.38069040695840156,
                                     0.61930959304159845, 0.83060469323313224, 0.96623475710157601};
  static constexpr double weight[6] = {0.085662246189585173, 0.18038078652406930, 0.23395696728634552,
                                       0.23395696728634552, 0.18038078652406930, 0.085662246189585173};
  double factorial = 1;
  for (int j = 2; j <= m; ++j) factorial *= j;
  std::array<double, 4> w{};
  for (int d = lo; d <= hi; ++d) {
    double total = 0;
    for (int g = 0; g < 6; ++g) {
      const double u = node[g];
      double basis = 1;
      for (int e = lo; e <= hi; ++e)
        if (e != d) basis *= (u - e) / static_cast<double>(d - e);
      total += weight[g] * std::pow(1 - u, m) / factorial * basis;
    }
    w[static_cast<std::size_t>(d + 1)] = total;
  }
  return w;
}

IntervalRules::IntervalRules(int m) {
  for (int lo : {-1, 0})
    for (int hi : {1, 2}) rules_[static_cast<std::size_t>((lo == -1) * 2 + (hi == 2))] = interval_rule(lo, hi, m);
}

}  // namespace sidc
