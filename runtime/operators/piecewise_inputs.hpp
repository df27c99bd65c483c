// Integrals on records with inputs held between samples, exact on each sample interval (thesis
// section 4-2: the process was recorded every 0.75 min and its input moved in steps).
//
// Relies on: ir/ir.hpp (each input's hold), records/sampled_record.hpp. Guarantees: on the
// interval [t_i, t_{i+1}] a `held` input is the constant x_i and a `linear` one the line through
// x_i and x_{i+1}. Where the input changes piece (a step of a held input, a change of slope of a
// linear one) an integrand holding it jumps, and the outputs it drives kink: no rule across such a
// sample integrates them well. So the record is cut into segments at those samples (only there:
// a held input that keeps its value for ten samples is one piece over ten intervals), and each
// interval's integral is taken from the integrand at the samples i-1 .. i+2 that lie in its
// segment, by the rule through them (the cubic inside a segment, as simpson.hpp's odd-sample rule;
// the parabola or the trapezoid at a segment's ends). A held input's own value at the right node
// is the piece's, not the next sample's: the integrand G_i(t_{i+d}) is read at sample i+d of piece
// record d, in which every such input is replaced by the piece of the interval that starts d
// samples earlier: x_d[k] = piece_{k-d}(t_k). A weight (t_{i+1} - s)^m / m! under the integral
// is integrated exactly against the rule's polynomial: integrating by parts,
// int_{t_i}^{t_{i+1}} F = h F(t_i) + int (t_{i+1} - s) F'(s) ds, so an integral of an integral
// (the twice-integrated form's int(int(x))) needs only the inner integrand's pieces, and int(x),
// int(int(x)), int(int(int(x))) of a held or linear x are exact.
#pragma once

#include <array>
#include <string>
#include <utility>

#include "ir/ir.hpp"
#include "ir/queries.hpp"  // piecewise_input(), first_piecewise_input()
#include "runtime/records/sampled_record.hpp"

namespace sidc {

// The stencil offsets d of the samples i + d around interval i.
inline constexpr std::array<int, 4> kPieceOffsets{-1, 0, 1, 2};

// The first held or linear input `t` holds (anywhere in it), or nullptr.
const ir::Signal* piecewise_input_of(const ir::Model& model, const ir::Term& t);

// True when `t` has an integral, at any depth, whose integrand holds a held or linear input: such
// a factor is continuous but kinked at every sample, and only the integrand's pieces, not the
// integral's, can be evaluated on the piece records.
bool has_piecewise_integral(const ir::Model& model, const ir::Term& t);

// Piece record d (d in kPieceOffsets): every held or linear input x replaced by
// piece_{k-d}(t_k) at each sample k; k - d outside the record is clamped to its ends, values a
// stencil never weighs.
SampledRecord piece_record(const SampledRecord& record, const ir::Model& model, int d);

// Per sample k of the record: 1 when some held or linear input starts a new piece there (its
// value, or for a linear input its slope, differs from the interval before); 0 elsewhere.
std::vector<unsigned char> piece_boundaries(const SampledRecord& record, const ir::Model& model);

// True when the model has a recorded input that is held or linear.
bool has_piecewise_inputs(const ir::Model& model);

// The weights of one interval's rule on the stencil nodes lo..hi (lo in {-1, 0}, hi in {1, 2}),
// indexed d + 1 (0 for nodes outside): int_0^1 (1 - u)^m / m! L_d(u) du, where L_d is the
// Lagrange polynomial of node d, so that int_{t_i}^{t_{i+1}} (t_{i+1} - s)^m / m! G(s) ds =
// h^(m+1) sum_d w[d+1] G(t_{i+d}), exact for cubic G. For m = 0 on four nodes: (-1, 13, 13, -1)/24.
std::array<double, 4> interval_rule(int lo, int hi, int m);

// The four rules of weight m an interval can have, by its nodes (lo, hi) (Evaluator::interval_nodes).
class IntervalRules {
 public:
  explicit IntervalRules(int m);
  const std::array<double, 4>& operator()(std::pair<int, int> nodes) const {
    return rules_[static_cast<std::size_t>((nodes.first == -1) * 2 + (nodes.second == 2))];
  }

 private:
  std::array<std::array<double, 4>, 4> rules_;
};

}  // namespace sidc
