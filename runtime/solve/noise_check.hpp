// The noise check: what the record's own noise does to the equation-error estimate.
//
// The thesis' fit (eq. 2-1.7) evaluates its operations on the noisy record, so its regressors are
// noisy too (errors in variables), and the same noise is in its residuals: the classical standard
// errors, which take the regressors as exact, can then be far too small, and the estimate biased.
// Neither shows in the residuals: a 120-sample oscillator at 0.8% noise, integrated twice, gives
// c with a standard error of 0.0012 whose estimate scatters by 0.0094 from one noise realization
// to the next, its residuals white. What shows it: the fit made again on copies of the records
// with noise of each output's estimated level added, every data-driven choice (arcs, subdomains)
// held as the fit made it. To first order the copies' estimates scatter about the fit's as the
// fit's own estimate scatters about the truth under that noise (a parametric bootstrap of the
// noise), and their mean shift is the bias the record's noise already gave (the noise's variance
// doubled: the first step of SIMEX, Cook and Stefanski, JASA 1994).
//
// Relies on: fit.hpp (FitOptions::same_choices_as); the noise levels the fit estimated (one per
// output and record; the inputs are taken as exact, as the fit takes them). Guarantees: the
// records are not changed; the copies' noise comes from a fixed seed (the same report every run);
// a fit that is streamed, or whose copies would refit more samples than the budget, or without
// noise, is not checked, and `not_run` says why.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "ir/ir.hpp"
#include "runtime/records/sampled_record.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {

struct NoiseCheckOptions {
  int replicates = 16;                   // copies refitted: their s.d. is known to about 1/sqrt(2*15) = 18%
  std::uint64_t seed = 0x51dc'0b1a5ULL;  // the copies' noise: the same every run
  std::size_t budget = 1'000'000;        // samples refitted in all (replicates x samples); beyond it, not run
  double narrow_above = 2;               // copies' s.d. beyond this many std. errors: the intervals are too narrow
  double biased_above = 1;               // a shift beyond this many of the larger of the two: a bias
};

struct NoiseCheck {
  struct Shift {
    std::string name;  // the fit's column (a parameter or an integration constant)
    double estimate = 0, standard_error = 0;
    double scatter = 0;      // s.d. of the copies' estimates: the estimate's own s.d. under the noise
    double shift = 0;        // their mean minus the estimate: the bias, to first order
    double shift_error = 0;  // the Monte Carlo error of that mean
    bool narrow = false;     // scatter above narrow_above standard errors
    bool biased = false;     // |shift| above biased_above of max(standard error, scatter) and three shift errors
    double ratio() const { return standard_error > 0 ? scatter / standard_error : INFINITY; }
  };
  bool ran = false;
  std::string not_run;  // why not, when it did not run
  int replicates = 0;
  std::vector<Shift> shifts;  // every group's columns, in order
  NoiseCheckOptions options;

  std::vector<std::string> narrow() const;
  std::vector<std::string> biased() const;
  bool found_trouble() const { return !narrow().empty() || !biased().empty(); }
  std::string statement() const;  // what it found and what to do
  std::string report() const;     // the report's section
};

// The check of `fitted` (a fit of `model` to `records` with `options`).
NoiseCheck check_noise(const ir::Model& model, const std::vector<SampledRecord>& records, const FitOptions& options, const FitSummary& fitted,
                       const NoiseCheckOptions& check = {});

}  // namespace sidc
