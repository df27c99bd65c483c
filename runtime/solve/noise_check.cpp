#include "runtime/solve/noise_check.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "runtime/parallel_ranges.hpp"

namespace sidc {

namespace {

std::string listed(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) out += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
  return out;
}

// The names of the shifts whose `flag` is set.
std::vector<std::string> flagged(const std::vector<NoiseCheck::Shift>& shifts, bool NoiseCheck::Shift::*flag) {
  std::vector<std::string> out;
  for (const auto& s : shifts)
    if (s.*flag) out.push_back(s.name);
  return out;
}

}  // namespace

std::vector<std::string> NoiseCheck::narrow() const { return flagged(shifts, &Shift::narrow); }

std::vector<std::string> NoiseCheck::biased() const { return flagged(shifts, &Shift::biased); }

std::string NoiseCheck::statement() const {
  if (!ran) return "not run: " + not_run;
  const std::vector<std::string> wide = narrow(), off = biased();
  if (wide.empty() && off.empty()) {
    double low = INFINITY, high = 0;
    for (const auto& s : shifts)
      if (std::isfinite(s.ratio())) low = std::min(low, s.ratio()), high = std::max(high, s.ratio());
    if (high < 0.5)
      return fmt::format("the copies scatter by only {:.2f} to {:.2f} of the std. errors and shift by less: the residuals are larger than the "
                         "record's noise explains (terms missing, a varying system, or noise the estimate misses), so the std. errors are "
                         "the misfit's; the validation and the residual analysis judge it",
                         low, high);
    return fmt::format("the classical intervals hold under the record's noise: the copies scatter by {:.2f} to {:.2f} of the std. errors "
                       "(too narrow above {:g}) and no estimate shifts beyond them",
                       low, high, options.narrow_above);
  }
  std::string out;
  if (!wide.empty()) {
    double largest = 0;
    for (const auto& s : shifts)
      if (s.narrow) largest = std::max(largest, s.ratio());
    out = fmt::format("the classical intervals of {} are up to {:.1f}x too narrow: the noise is in the evaluated operations as well as in the "
                      "residuals (errors in variables); take the copies' s.d. as {} std. error{}",
                      listed(wide), largest, wide.size() > 1 ? "their" : "its", wide.size() > 1 ? "s" : "");
  }
  if (!off.empty()) {
    double largest = 0;
    for (const auto& s : shifts)
      if (s.biased) largest = std::max(largest, std::abs(s.shift) / std::max(s.standard_error, s.scatter));
    out += fmt::format("{}{} {} by {:.1f} s.d. with the noise doubled: the record's noise biases {} by about that much",
                       out.empty() ? "" : "; ", listed(off), off.size() > 1 ? "shift" : "shifts", largest, off.size() > 1 ? "them" : "it");
  }
  return out + "; --refine (output error) is free of both";
}

std::string NoiseCheck::report() const {
  if (!ran) return "noise check (errors in variables): " + statement() + "\n";
  std::string out = fmt::format(
      "noise check (errors in variables): the fit again on {} copies of the records with noise of each output's estimated level added,\n"
      "  arcs and subdomains as chosen: the copies scatter about the estimate as it scatters about the truth under that noise (a\n"
      "  parametric bootstrap, honest where the classical std. errors take the evaluated operations as exact), and their mean shift\n"
      "  is, to first order, the bias the record's noise already gave (SIMEX's first step)\n",
      replicates);
  out += fmt::format("  {:<12} {:>14} {:>12} {:>14} {:>13} {:>12} {:>13}\n", "parameter", "estimate", "std. error", "copies' s.d.", "x std. error",
                     "shift", "shift / s.d.");
  for (const auto& s : shifts)
    out += fmt::format("  {:<12} {:>14.6g} {:>12.4g} {:>14.4g} {:>13.2f} {:>12.3g} {:>13.2f}{}\n", s.name, s.estimate, s.standard_error, s.scatter,
                       s.ratio(), s.shift, s.shift / std::max(s.standard_error, s.scatter),
                       s.narrow && s.biased ? "   too narrow, biased" : s.narrow ? "   too narrow" : s.biased ? "   biased" : "");
  return out + "  " + statement() + "\n";
}

NoiseCheck check_noise(const ir::Model& model, const std::vector<SampledRecord>& records, const FitOptions& options, const FitSummary& fitted,
                       const NoiseCheckOptions& check) {
  NoiseCheck out;
  out.options = check;
  if (!fitted.is_solution_usable()) {
    out.not_run = "the fit has no usable solution";
    return out;
  }
  for (const auto& g : fitted.groups)
    if (!g.streamed.empty()) {
      out.not_run = "the fit was streamed (a record this long is not refitted on copies)";
      return out;
    }
  std::size_t samples = 0;
  for (const auto& r : records) samples += r.time.size();
  if (samples * static_cast<std::size_t>(check.replicates) > check.budget) {
    out.not_run = fmt::format("{} copies of {} samples exceed the check's budget of {} samples refitted", check.replicates, samples, check.budget);
    return out;
  }
  // The outputs' noise per record; the inputs are taken as exact, as the fit takes them.
  std::vector<std::map<std::string, double>> noise(records.size());
  bool any = false;
  for (std::size_t r = 0; r < records.size() && r < fitted.operators.size(); ++r)
    for (const auto& s : fitted.operators[r].noise)
      for (const auto& signal : model.signals)
        if (signal.name == s.signal && signal.kind == ir::Signal::Kind::output && s.level.sigma > 0 && std::isfinite(s.level.sigma)) {
          noise[r][s.signal] = s.level.sigma;
          any = true;
        }
  if (!any) {
    out.not_run = "no output of the records has an estimated noise level above 0";
    return out;
  }

  FitOptions o = options;
  o.same_choices_as = &fitted;
  o.progress = {};
  o.share = nullptr;
  // Every copy's noise drawn first, in the order one thread drawing copy after copy would draw it
  // (record, output, sample), so that the copies, refitted on every core, are the same bits on any
  // number of them.
  std::size_t per_copy = 0;
  for (std::size_t r = 0; r < records.size(); ++r)
    for (const auto& entry : noise[r]) per_copy += records[r].signals.at(entry.first).size();
  const auto replicates = static_cast<std::size_t>(check.replicates);
  std::vector<double> draws(per_copy * replicates);
  std::mt19937_64 random(check.seed);
  std::normal_distribution<double> normal;
  for (double& d : draws) d = normal(random);

  std::vector<std::vector<double>> values(replicates);  // per copy, every group's columns in order
  std::vector<std::string> failures(replicates);        // why a copy could not be fitted ("" if it was)
  for_parallel_ranges(
      replicates, 0,
      [&](std::size_t first, std::size_t last) {
        std::vector<SampledRecord> copies = records;
        for (std::size_t b = first; b < last; ++b) {
          const double* d = draws.data() + b * per_copy;
          for (std::size_t r = 0; r < records.size(); ++r)
            for (const auto& [name, sigma] : noise[r]) {
              auto& copy = copies[r].signals.at(name).owned();
              const Column& original = records[r].signals.at(name);
              for (std::size_t i = 0; i < copy.size(); ++i) copy[i] = original[i] + sigma * *d++;
            }
          auto refit = fit(model, copies, o);
          if (auto* problem = std::get_if<Diagnostic>(&refit)) {
            failures[b] = "a copy with noise added could not be fitted: " + problem->message;
            continue;
          }
          const FitSummary& s = std::get<FitSummary>(refit);
          if (!s.is_solution_usable()) {
            failures[b] = "a copy with noise added has no usable solution (its design is rank deficient)";
            continue;
          }
          for (const auto& g : s.groups)
            for (const auto& p : g.summary.parameters) values[b].push_back(p.value);
        }
      },
      0);
  for (const auto& why : failures)
    if (!why.empty()) {
      out.not_run = why;
      return out;
    }

  std::size_t k = 0;
  const double n = static_cast<double>(values.size());
  for (const auto& g : fitted.groups)
    for (const auto& p : g.summary.parameters) {
      NoiseCheck::Shift s;
      s.name = p.name;
      s.estimate = p.value;
      s.standard_error = p.standard_error;
      double mean = 0, squares = 0;
      for (const auto& v : values) mean += v[k];
      mean /= n;
      for (const auto& v : values) squares += (v[k] - mean) * (v[k] - mean);
      s.shift = mean - p.value;
      s.scatter = values.size() > 1 ? std::sqrt(squares / (n - 1)) : 0.0;
      s.shift_error = s.scatter / std::sqrt(n);
      const bool estimable = std::isfinite(s.standard_error) && s.standard_error > 0;
      s.narrow = estimable && s.scatter > check.narrow_above * s.standard_error;
      s.biased = estimable && std::abs(s.shift) > check.biased_above * std::max(s.standard_error, s.scatter) && std::abs(s.shift) > 3 * s.shift_error;
      out.shifts.push_back(std::move(s));
      ++k;
    }
  out.ran = true;
  out.replicates = check.replicates;
  return out;
}

}  // namespace sidc
