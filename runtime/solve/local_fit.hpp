// Local fits (thesis chapter V: "systems characterized by time varying parameters provided the
// parameters are slowly varying ... by determining the parameters in a local neighborhood"): the
// model fitted on every window of a given width along each record, or recursively with exponential
// forgetting, with the operators, form and weights of the global fit (fit.hpp).
//
// Relies on: design.hpp (the same rows as the global fit: block_evaluator.hpp for the derivative
// and integrated forms, weak_design.hpp for the weak form, whose subdomains count by their centre),
// sliding_factor.hpp (rows entering and leaving a triangular factor).
//
// Guarantees:
// - Window k of a record covers the fit window's samples [k S, k S + W) (W = width / step,
//   rounded; S the stride), every equation of the group; its row holds the estimates, standard
//   errors, G (eq. 2-1.7), the rows n and the rank. A rank-deficient window carries no estimate and
//   says so (rank < p); nothing else is NaN but a standard error where n <= p (no residual
//   degrees of freedom; with forgetting, n is the weighted count of rows and can be below p).
// - Cost per window step O(S p^2): the factor is updated with the rows entering and downdated with
//   those leaving. The windows are cut into pieces (about four turnovers of the window each) that
//   start from a fresh factor, shared out over threads; each piece also computes the first window
//   of the next piece, so the updated and the fresh factor are compared at every piece border: the
//   largest relative difference of the estimates is reported (drift), and a downdate that would
//   lose accuracy (sliding_factor.hpp) is replaced by a fresh factor of that window and counted.
// - With forgetting (lambda in (0, 1)), estimate k uses every sample up to k S, sample j weighted
//   lambda^(kS - j) (the rows by sqrt of it); a piece starts log(1e-32)/log(lambda) samples before
//   its first estimate, so that what it does not see weighs less than rounding in R.
// - The pieces are laid out from the windows alone (never from the machine's cores), so the same
//   record gives the same digits everywhere.
// - Memory: the rows of a chunk of samples per thread, and the results (2p + 4 doubles a window).
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <utility>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "ir/ir.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {

struct LocalFitOptions {
  double width = 0;                // window length in the record's time unit (ignored with forget)
  std::size_t stride = 1;          // samples from one window (or recursive estimate) to the next
  std::optional<double> forget;    // lambda in (0, 1): exponential forgetting instead of windows
  int threads = 0;                 // 0: one per core, at most 8
  std::size_t piece_turnovers = 4; // a fresh factor every this many window lengths
  // Called on the calling thread as pieces finish: the record, its windows done and in all.
  std::function<void(const std::string& what, std::size_t done, std::size_t total)> progress;
};

// Vectors whose resize leaves new elements uninitialised: the results of 10^6 windows are written
// once each by the threads, and an initial fill would be a serial pass over a few hundred MB.
template <class T>
struct UninitialisedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitialisedAllocator<U>;
  };
  template <class U, class... Args>
  void construct(U* at, Args&&... args) {
    if constexpr (sizeof...(Args) == 0) ::new (static_cast<void*>(at)) U;
    else ::new (static_cast<void*>(at)) U(std::forward<Args>(args)...);
  }
};
using LocalValues = std::vector<double, UninitialisedAllocator<double>>;

// One record's windows for one group.
struct LocalRecordFit {
  std::string path;
  std::size_t window_samples = 0;          // W (for forgetting: the effective 1 / (1 - lambda))
  LocalValues t_center, G, n;             // per window; n: rows (weighted count with forgetting)
  std::vector<int> rank;
  LocalValues estimates, standard_errors;  // windows x p, row by row; NaN where rank < p
  std::size_t windows() const { return t_center.size(); }
};

struct LocalGroupFit {
  std::vector<std::size_t> equations;
  std::vector<std::string> columns;
  std::vector<ParameterIndex> column_parameters;
  std::vector<LocalRecordFit> records;
};

struct LocalFitSummary {
  LocalFitOptions options;
  std::vector<LocalGroupFit> groups;
  std::size_t fresh_factors = 0;       // pieces started and downdates replaced
  std::size_t refused_downdates = 0;   // downdates that would have lost accuracy
  std::size_t drift_checks = 0;
  double max_drift = 0;                // largest |x_updated - x_fresh|_inf / |x_fresh|_inf at a piece border
  std::size_t rank_deficient = 0;      // windows without estimates
  double seconds = 0;                  // wall time of the local fits
  int threads = 1;
  std::string report() const;          // the text section of sidc fit's report
  std::string group_report(std::size_t group) const;  // its table for one group (the HTML report's)
};

// Before the global fit: a window longer than a record's samples (`options` given: than its fit
// window, the samples the model's derivatives leave within from/to), or, for equations of the
// derivative and integrated forms, with fewer rows than a group's parameters. A weak-form window's
// rows are subdomains, known once they are chosen: local_fit() checks those.
std::optional<Diagnostic> check_local_window(const ir::Model& model, const std::vector<SampledRecord>& records, const LocalFitOptions& local,
                                             const FitOptions* options = nullptr);

std::variant<LocalFitSummary, Diagnostic> local_fit(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                    const FitOptions& options, const LocalFitOptions& local);

}  // namespace sidc
