// `select`: determination of operations (thesis section 2-3). Over the candidate operations of a
// general model, find for every subset size the subset with the smallest G(a) (eq. 2-1.7), rank
// the sizes by a relative-G elbow, AIC, BIC and K-fold cross-validation over blocks of time, name
// the operations found non-contributory, flag candidates that only absorb drift, and say how
// stable the choice is by a bootstrap over time blocks.
//
// Relies on: a compiled model and records bound to its signals (as fit: runtime/solve/fit.hpp,
// FitOptions), the design builder (runtime/solve/design.hpp) for the columns and rows,
// TriangularAccumulator for one triangle per block of time, and the three search methods on
// triangles: best_subset.hpp (exact), sequential_threshold.hpp (STLSQ), forward_regression.hpp (FROLS);
// size_rule.hpp (the elbow and the drift test).
//
// Guarantees:
// - The rows are those fit uses (same window, weights, groups of equations sharing parameters,
//   integration constants per record); they are evaluated once and folded into F contiguous time
//   blocks, F = K * ceil(10 / K) for K folds (at least 10 blocks, K whole folds). After that,
//   nothing depends on n: the full problem is the merge of all block triangles, a cross-validation
//   training set the merge of the other folds' triangles, a test error G at the training solution
//   of the held-out fold's triangle, a bootstrap replicate the merge of F blocks drawn with
//   replacement.
// - Integration constants are always kept (they are not operations of the system); so are the
//   parameters named in `required` (a group member requires its group). `dropped` parameters are
//   removed before the search. A group's parameters enter or leave together.
// - Sizes count parameters (columns). For each size, the reported G is the exact minimum (exact
//   method; within BestSubsetOptions::tolerance * G(0)) or the best the heuristic found (STLSQ,
//   FROLS). AIC = n log(G/n) + 2k, BIC = n log(G/n) + k log n (least_squares.hpp's convention).
//   CV(k) = sum over folds of the held-out G / n: mean squared prediction error per row of the
//   size-k subset chosen afresh on each training set. The CV rule picks the smallest size whose
//   CV is within one standard error (over the folds) of the least CV.
// - The default rule is `elbow`: the smaller of the relative-G elbow (size_rule.hpp) and the CV
//   choice (the elbow alone with --folds 0). CV stays right when the rows' errors are correlated
//   noise (moving-arc derivatives, integrals), where AIC and BIC keep extra terms; the elbow stays
//   right when they are not noise at all (a noise-free record leaves only the operators' smooth
//   truncation error, which extra terms fit and CV then keeps). docs/selection.md has the numbers.
// - Drift absorbers: a candidate column whose values over every record's window are nearly a
//   polynomial in t of degree <= (integrations + 1) (the operation before integration nearly a
//   line: share of its sum of squares >= drift_share, size_rule.hpp) is flagged; in an integrated equation it is set aside before the search unless it is required or
//   keep_drift is set (its coefficient would measure the drift of the integrated noise, which
//   grows like a polynomial in t, not an operation of the system). In the derivative form it is
//   only flagged.
// - Deterministic: the bootstrap draws from std::mt19937_64 seeded by `seed`; the same options give
//   the same output on any run.
// - Never throws on bad data: problems with the records come back as a Diagnostic, a search that
//   cannot run (too many candidates for exact search) in SelectSummary::message.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "ir/ir.hpp"
#include "runtime/select/best_subset.hpp"
#include "runtime/select/size_rule.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/solve/fit.hpp"

namespace sidc {

enum class SelectionMethod { automatic, exact, stlsq, frols };
enum class SizeRule { aic, bic, cv, elbow };
const char* to_string(SelectionMethod method);
const char* to_string(SizeRule rule);

// Free units (candidate units not required) up to which `automatic` searches exactly; above it,
// FROLS. Measured worst case of exact search (every subset evaluated, no cut: bench/select_bench.cpp,
// Release, this machine) is 2^24 subsets in 2.0 s, about 0.12 us a subset, so 2^26 takes about
// 8 s, and the 6 searches of the default 5-fold cross-validation about 50 s: within a minute.
// Real problems cut most subsets (the 24-candidate thesis search evaluates 2 to 4% of them).
inline constexpr int kExactSearchUnitLimit = 26;

struct SelectOptions {
  FitOptions fit;
  SelectionMethod method = SelectionMethod::automatic;
  std::vector<std::string> required;  // parameter names kept in every subset
  std::vector<std::pair<std::string, std::vector<std::string>>> groups;  // name -> parameters entering together
  std::vector<std::string> dropped;   // parameter names removed before the search
  int folds = 5;                      // K for cross-validation over contiguous time blocks (>= 2), 0 = off
  int bootstrap = 0;                  // replicates (0 = off)
  std::uint64_t seed = 1;
  int max_size = -1;                  // largest subset size reported (-1 = all)
  SizeRule rule = SizeRule::elbow;    // which criterion names the non-contributory operations
  double elbow_share = kElbowShare;   // the elbow's step leaves at most this share of log(G/G_full) (size_rule.hpp)
  double drift_share = kDriftAbsorberShare;   // a candidate this close to a polynomial in t is a drift absorber
  bool keep_drift = false;            // search drift absorbers of integrated equations too
  double tolerance = 1e-10;           // of the exact search, relative to G(0) (best_subset.hpp)

  // Hook for ranking by free-run simulation error (runtime/simulate/): when set, called
  // for the best subset of every size with the parameters (their indices) and values of that
  // subset (all others zero) and the group index; its value (smaller is better) is reported in a `sim` column
  // and can be the size rule later. sidc select --simulate sets it (cli/select_command.cpp).
  std::function<std::optional<double>(std::size_t group, const std::vector<ParameterIndex>& parameters, const std::vector<double>& values)>
      simulation_error;

  bool is_valid(std::string* why) const;
};

struct SizeRow {
  int size = 0;                          // parameters in the subset
  std::vector<std::string> parameters;   // the best subset of this size
  std::vector<ParameterIndex> indices;   // beside parameters: the model parameter (and record) of each
  std::vector<double> values;            // their least-squares values
  int rank = 0;
  double G = 0;                          // eq. 2-1.7
  double standard_error = 0;             // sqrt(G/n) (thesis, Table 4-1.2)
  double aic = 0, bic = 0;
  double cv = 0;                         // NaN when cross-validation is off or a fold had no subset of this size
  double cv_standard_error = 0;          // of cv: s.d. of the folds' mean squared errors / sqrt(K)
  std::optional<double> simulation;      // from the hook
  double elbow_left = 0;                 // share of log(G_prev / G_full) left after this size's step (NaN for the first)
};

// A candidate whose values over the window are nearly a polynomial in t.
struct DriftAbsorber {
  std::string column;
  double share = 0;       // of the operation's sum of squares a line a + b t explains (the least over records and equations)
  int degree = 0;         // of the polynomial: integrations + 1
  bool set_aside = false; // left out of the search (integrated equation, not required, no keep_drift)
};

struct GroupSelection {
  std::vector<std::size_t> equations;
  std::vector<std::string> columns;        // every parameter of the group
  std::vector<ParameterIndex> column_parameters;  // beside columns: the model parameter (and record) of each
  std::vector<std::string> operations;     // the operation each column multiplies, printed
  std::vector<std::string> required, dropped;  // by column name (dropped: by --drop)
  std::vector<DriftAbsorber> drift;        // flagged candidates, in column order
  std::size_t n = 0;
  SelectionMethod method = SelectionMethod::exact;  // the one used
  std::size_t blocks = 0;
  std::vector<SizeRow> rows;               // by increasing size; sizes that cannot occur are absent
  // Indices into rows: least AIC, least BIC, the one-standard-error CV choice (the smallest size
  // whose CV is within one standard error of the least CV), the least CV, the least simulation
  // error, the relative-G elbow.
  int best_aic = -1, best_bic = -1, best_cv = -1, least_cv = -1, best_simulation = -1, best_elbow = -1;
  int chosen = -1;                         // by the rule
  std::string reason;                      // why the rule chose that size, in words (for the report)
  std::vector<std::string> non_contributory;  // candidates outside the chosen subset (dropped ones not included)
  // Bootstrap: per column, the share of replicates whose chosen subset contains it.
  int bootstrap_replicates = 0;
  std::vector<double> bootstrap_frequency;
  // The path of the heuristic methods, one line per step, and search statistics.
  std::vector<std::string> path;
  std::size_t nodes = 0, subsets_total = 0;
  double search_seconds = 0;               // the search on all rows (not CV or bootstrap)
  double total_seconds = 0;                // with CV and bootstrap
};

struct SelectSummary {
  std::string model_name;
  SizeRule rule = SizeRule::elbow;
  int folds = 0;
  double elbow_share = kElbowShare;
  std::vector<GroupSelection> groups;
  std::string message;  // non-empty when the search could not run (then `groups` is incomplete)
  bool ok() const { return message.empty(); }
  std::string report() const;
};

// The names `required`, `groups` and `dropped` may use: the model's parameters (not integration constants).
std::vector<std::string> selectable_parameters(const ir::Model& model);

std::variant<SelectSummary, Diagnostic> select_operations(const ir::Model& model, const std::vector<SampledRecord>& records,
                                                          const SelectOptions& options);

}  // namespace sidc
