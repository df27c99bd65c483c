// sum_k w_k * S_k(point) for Sums S_k with weights w_k: an equation's side with the parameter
// values substituted (w_k = a_k, S_k the operation a_k multiplies), as the simulation evaluates it
// at every stage of every step (runtime/simulate/simulate.cpp).
//
// Relies on: runtime/operators/point_evaluator.hpp for the layout, the instant and every factor
// that is not a plain signal derivative (functions, powers of sums, guards, sign(), t, initial
// values). Guarantees: compiled once into a straight-line program over registers: each distinct
// factor of all the parts is evaluated once per evaluation (y read once, not once per term that
// has it), each distinct integer power of it once, from one chain of products (y, y^2 = y*y,
// y^3 = y^2*y, ...: the same products PointSum's integer_power takes, so the same bits), and then
// every term as the product of its registers. The value equals, bit for bit, the sum over parts of
// w_k * PointSum(S_k).evaluate(at) (the same products and sums in the same order, a guard that is
// off zeroing its term whatever the other factors are), so a run is unchanged by it; only the
// work is: a 20-term right-hand side took about 0.5 us as 21 PointSums and takes a tenth of that.
// part_value(k) is S_k at the last evaluation (d/d w_k of the whole, for the sensitivities).
#pragma once

#include <array>
#include <map>
#include <optional>
#include <vector>

#include "diagnostics/diagnostic.hpp"
#include "ir/ir.hpp"
#include "runtime/operators/point_evaluator.hpp"

namespace sidc {

class WeightedPointSum {
 public:
  // Adds w * s as the next part; `parameter` is what the caller says w is (-1: none). An empty
  // `s` is a part of value 0.
  std::optional<Diagnostic> add(double weight, int parameter, const ir::Sum& s, PointLayout& layout, const PointCompileOptions& options);

  double evaluate(const PointInstant& at);

  std::size_t parts() const { return parts_.size(); }
  bool empty() const { return parts_.empty(); }
  int parameter(std::size_t part) const { return parts_[part].parameter; }
  double part_value(std::size_t part) const { return part_values_[part]; }

 private:
  // A register's value: a slot of the instant, a factor evaluated by its own one-factor PointSum,
  // or the previous power of a base times the base (or std::pow for powers beyond the chain).
  struct Load {
    int slot = 0, target = 0;
  };
  struct Compound {
    PointSum factor;  // value = the factor itself (a sum of one term with one factor, power 1)
    int target = 0;
  };
  // x^2 .. x^top of one base by one chain of products kept in a CPU register (a chain through the
  // register file in memory would wait on every store); target[e] is where x^e goes, -1 if unused.
  struct Chain {
    int base = 0, top = 1;
    std::array<int, 9> target{-1, -1, -1, -1, -1, -1, -1, -1, -1};
  };
  struct Pow {  // a power beyond the chain: std::pow, as PointSum's integer_power takes it
    int base = 0, exponent = 1, target = 0;
  };
  struct TermFactor {
    int reg = 0;
    bool guard = false;  // a guard: its value is 0 or 1 (or NaN) and zeroes the term when 0
  };
  struct Term {
    double coefficient = 1;
    int first = 0, count = 0;  // factors_
  };
  struct Part {
    double weight = 1;
    int parameter = -1;
    int first = 0, count = 0;  // terms_
  };

  double exact_term(const Term& t) const;

  int base_register(const ir::Factor& f, const ir::Term& t, PointLayout& layout, const PointCompileOptions& options,
                    std::optional<Diagnostic>& problem);
  int power_register(int base, int exponent);

  std::vector<Load> loads_;
  std::vector<Compound> compounds_;
  std::vector<Chain> chains_;
  std::vector<Pow> pows_;
  std::vector<TermFactor> factors_;
  std::vector<Term> terms_;
  std::vector<Part> parts_;
  std::vector<double> registers_, part_values_;
  // Every term as coefficient * r[a] * r[b] * ... padded to `width_` registers with one that holds
  // 1 (exact): one plain loop of products, ILP across terms; a NaN product (0 * inf, which
  // PointSum's guarded product keeps 0) is taken again by exact_term(), and so are the terms in
  // exact_terms_ (a guard, or more than four factors), whose plain product is not used.
  int width_ = 1;
  std::vector<std::size_t> exact_terms_;
  int one_ = -1;                   // the register holding 1
  std::vector<int> padded_;        // terms_.size() * width_ registers
  std::vector<double> coefficients_;  // of terms_, contiguous
  std::vector<double> term_values_;
  std::map<ir::Factor, int> base_of_;              // factor -> register
  std::map<std::pair<int, int>, int> power_of_;    // (base register, exponent) -> register
};

}  // namespace sidc
