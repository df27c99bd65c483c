// The weak form's test functions (compiler/weak_pass.hpp): where the subdomains lie, how wide they
// are, and the quadrature weights that integrate phi_j^(k) * g over each.
//
// phi(t) = (1 - s^2)^p with s = (t - c_j) / h on [c_j - h, c_j + h], zero outside: it and its first
// p - 1 derivatives vanish at both ends, so moving k <= p - 1 derivatives onto it by parts leaves
// no boundary term, and the trapezoid rule over its 2m + 1 samples (h = m * step) converges fast
// (the integrand's derivatives vanish at the ends: Euler-Maclaurin). The width is chosen from the
// data (Messenger and Bortz, Weak SINDy, 2021, choose it from the spectrum's corner too): the
// recorded outputs' spectrum (Welch's average of Hann-windowed periodograms) rises above its
// white-noise floor (the median power of the upper half band, where a record sampled fast enough
// for its dynamics holds only noise) up to a corner frequency f_c; phi, close to a Gaussian of
// standard deviation h / sqrt(2p), is made to pass what lies below f_c and cut what lies above,
// its transform falling to e^-2 at f_c: h = sqrt(2p) / (pi f_c). On a noise-free record f_c is
// where the spectrum meets the rounding floor, the subdomains are as narrow as the quadrature
// allows, and the weak equation is the derivative form's, integrated exactly; the half-width is
// then at least a quarter period of the outputs' mean frequency (the support half a period). Subdomains overlap:
// one starts every m/4 samples, so the rows cover the record evenly.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "diagnostics/diagnostic.hpp"

namespace sidc {

struct TestFunctionGrid {
  std::size_t half_width = 0;        // m: samples each side of a centre; the support has 2m + 1
  int degree = 0;                    // p
  std::vector<std::size_t> centres;  // sample indices of the centres, relative to the values' start
  double corner_frequency = 0;       // f_c (1/time) the width was chosen from; 0 when not measured
  std::string reason;                // how the width was chosen, for the report
};

// The grid for `outputs` (each output's values over the fit window, uniformly sampled at `step`)
// when derivatives up to `highest_order` are moved onto phi. A Diagnostic when the window is too
// short for even the narrowest subdomain (`fewest_rows` subdomains of the narrowest width).
std::variant<TestFunctionGrid, Diagnostic> choose_test_functions(const std::vector<std::span<const double>>& outputs,
                                                                 std::size_t samples, double step, int highest_order,
                                                                 std::size_t fewest_rows, std::string_view record);

// The trapezoid weights of phi^(k) over the support, 2m + 1 of them: sum_i w[i] g[c - m + i]
// approximates the integral of phi_j^(k) * g over subdomain j.
std::vector<double> test_function_weights(const TestFunctionGrid& grid, int k, double step);

// The corner frequency of one signal's spectrum (see above); 0 when the signal holds no power
// above its noise floor (then the widest subdomains are best), Nyquist when it never meets it.
double corner_frequency(std::span<const double> values, double step);

}  // namespace sidc
