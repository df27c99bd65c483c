// The eleven NIST StRD linear regression sets fitted through the `sidc` binary, exactly as a user
// fits them (`sidc compile X.sid -o DIR/X.sidc.json`, then `sidc fit DIR/X.sidc.json --out DIR`),
// and scored in correct significant digits (LRE, McCullough 1998) like Ceres' examples/nist.cc.
//
// Relies on: the sidc binary (SIDC_BINARY, the CMake target's file); tests/nist (SIDC_NIST_DIR)
// holding models/<Set>.sid (one static model per set: no derivative, no integral, no time; rows
// are numbered), data/<Set>.csv (the .dat data block, made as tests/nist/README.md says) and
// data/<Set>.dat (the certified values, read with nist_dataset.hpp, the library-level test's
// reader); the fit.json format of `sidc fit --out` (groups[0].parameters[].{name, estimate,
// standard_error}, groups[0].statistics, groups[0].termination) and the report it prints.
// Guarantees: the source tree is never written (every file goes to a fresh temporary folder,
// removed when the set passes and kept, with its path printed, when it fails); for every certified
// parameter, standard deviation, the residual SD and R^2 it prints the certified value, sidc's
// value and the LRE, and fails when any LRE is below 9 digits (7 on Filip: the powers of x rounded
// to double leave about 7.6, see docs/accuracy.md). After all sets, a summary table (Markdown, the
// one in docs/accuracy.md "Through the sidc binary") gives every LRE of every set.
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "support/shell.hpp"
#include <nlohmann/json.hpp>

#include "nist_dataset.hpp"

namespace {

namespace fs = std::filesystem;
using sidc::testing::read_text;
using sidc::testing::shell_quoted;
using nlohmann::json;
using sidc::nist::log_relative_error;

const std::vector<std::string> kSets = {"Norris",   "Pontius",  "NoInt1",   "NoInt2",   "Filip",   "Longley",
                                        "Wampler1", "Wampler2", "Wampler3", "Wampler4", "Wampler5"};

// The issue's thresholds. Filip's design, once x^k is rounded to double, supports about 7.6
// digits whatever the arithmetic (docs/accuracy.md, "The ceiling of the data").
double required_digits(const std::string& set) { return set == "Filip" ? 7.0 : 9.0; }

// Runs a command with stdout and stderr in `log`; returns "" on exit status 0, else what to show.
std::string run(const std::string& command, const fs::path& log) {
  const int status = std::system((command + " >" + shell_quoted(log.string()) + " 2>&1").c_str());
  if (status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0) return "";
  const int code = status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : status;
  return fmt::format("command failed (exit status {}): {}\n{}", code, command, read_text(log));
}

// sidc's name for certified parameter "Bk": the family member b[k], or the plain name bk (NoInt1/2,
// whose only parameter B1 is declared `param b1`).
bool names_match(const std::string& sidc_name, const std::string& certified) {
  const std::string index = certified.substr(1);
  return sidc_name == "b[" + index + "]" || sidc_name == "b" + index;
}

// What one set scored, kept for the summary table printed after all sets.
struct SetScores {
  int n = 0, p = 0;
  double condition_before = 0, condition_after = 0, digits_lost = 0;
  std::vector<double> estimates, deviations;
  double residual_sd = 0, r_squared = 0;
  double minimum() const {
    double m = std::min(residual_sd, r_squared);
    for (double v : estimates) m = std::min(m, v);
    for (double v : deviations) m = std::min(m, v);
    return m;
  }
};
std::map<std::string, SetScores>& all_scores() {
  static std::map<std::string, SetScores> scores;
  return scores;
}

std::string joined(const std::vector<double>& values) {
  if (!values.empty() && std::all_of(values.begin(), values.end(), [&](double v) { return v == values.front(); }) &&
      values.size() > 2) {
    return fmt::format("{:.1f} (all {})", values.front(), values.size());
  }
  std::string out;
  for (double v : values) out += fmt::format("{}{:.1f}", out.empty() ? "" : " ", v);
  return out;
}

// After all sets: one Markdown row per set (the table in docs/accuracy.md).
class SummaryTable : public ::testing::Environment {
 public:
  void TearDown() override {
    if (all_scores().empty()) return;
    fmt::print("\nThrough the sidc binary: LRE (correct significant digits, capped at 15) of every certified value\n");
    fmt::print("| set | n, p | condition before / after scaling | digits lost (report) | estimates B0..Bk | "
               "std. deviations | residual SD | R^2 | minimum (required) |\n");
    fmt::print("|---|---|---|---|---|---|---|---|---|\n");
    for (const std::string& set : kSets) {
      const auto found = all_scores().find(set);
      if (found == all_scores().end()) continue;
      const SetScores& s = found->second;
      fmt::print("| {} | {}, {} | {:.3g} / {:.3g} | {:.1f} | {} | {} | {:.1f} | {:.1f} | {:.1f} ({:.0f}) |\n", set, s.n, s.p,
                 s.condition_before, s.condition_after, s.digits_lost, joined(s.estimates), joined(s.deviations),
                 s.residual_sd, s.r_squared, s.minimum(), required_digits(set));
    }
  }
};
[[maybe_unused]] ::testing::Environment* const summary_table = ::testing::AddGlobalTestEnvironment(new SummaryTable);

class SidcBinaryNist : public ::testing::TestWithParam<std::string> {};

TEST_P(SidcBinaryNist, MatchesCertifiedValuesToTheRequiredDigits) {
  const std::string set = GetParam();
  const fs::path nist(SIDC_NIST_DIR);
  const sidc::nist::Dataset dataset = sidc::nist::read_dataset((nist / "data" / (set + ".dat")).string());
  ASSERT_EQ(dataset.error, "") << set << ".dat";

  // A fresh folder per set: mkdtemp makes it atomically, so parallel runs never share one.
  std::string pattern = (fs::temp_directory_path() / ("sidc_nist_" + set + "_XXXXXX")).string();
  ASSERT_NE(mkdtemp(pattern.data()), nullptr) << "cannot create a temporary folder " << pattern;
  const fs::path work(pattern);

  const std::string sidc = shell_quoted(SIDC_BINARY);
  const fs::path compiled = work / (set + ".sidc.json");
  const fs::path out = work / "fit";
  const std::string compile_failure = run(
      sidc + " compile " + shell_quoted((nist / "models" / (set + ".sid")).string()) + " -o " + shell_quoted(compiled.string()),
      work / "compile.txt");
  ASSERT_EQ(compile_failure, "") << "kept " << work;
  const std::string fit_failure =
      run(sidc + " fit " + shell_quoted(compiled.string()) + " --out " + shell_quoted(out.string()), work / "fit.txt");
  ASSERT_EQ(fit_failure, "") << "kept " << work;

  json fit;
  try {
    fit = json::parse(read_text(out / "fit.json"));
  } catch (const json::exception& e) {
    FAIL() << "fit.json does not parse: " << e.what() << "; kept " << work;
  }
  ASSERT_TRUE(fit.contains("groups") && fit["groups"].size() == 1) << "expected one group; kept " << work;
  const json& group = fit["groups"][0];
  const json& parameters = group["parameters"];
  const json& statistics = group["statistics"];
  EXPECT_EQ(group["termination"].get<std::string>(), "success") << group["message"];
  ASSERT_EQ(parameters.size(), dataset.parameter_names.size()) << "kept " << work;
  EXPECT_EQ(statistics["n"].get<int>(), static_cast<int>(dataset.y.size())) << "every data row is one equation row";
  EXPECT_EQ(statistics["rank"].get<int>(), static_cast<int>(dataset.parameter_names.size()));

  SetScores scores;
  scores.n = statistics["n"].get<int>();
  scores.p = statistics["p"].get<int>();
  scores.condition_before = statistics["condition_before_scaling"].get<double>();
  scores.condition_after = statistics["condition_after_scaling"].get<double>();
  scores.digits_lost = statistics["digits_lost_estimate"].get<double>();

  const double required = required_digits(set);
  fmt::print("\n{} through sidc (n = {}, p = {}): condition {:.3g} before scaling, {:.3g} after; {:.1f} digits lost; {}\n",
             set, scores.n, scores.p, scores.condition_before, scores.condition_after, scores.digits_lost,
             group["arithmetic"].get<std::string>());
  fmt::print("  {:<14} {:>24} {:>24} {:>6}\n", "value", "certified", "sidc", "LRE");
  const auto score = [&](const std::string& label, double certified, double estimate) {
    const double digits = log_relative_error(estimate, certified);
    fmt::print("  {:<14} {:>24.15g} {:>24.17g} {:>6.1f}{}\n", label, certified, estimate, digits,
               digits < required ? "  < required" : "");
    EXPECT_GE(digits, required) << set << " " << label << ": certified " << fmt::format("{:.15g}", certified)
                                << ", sidc " << fmt::format("{:.17g}", estimate);
    return digits;
  };
  for (std::size_t k = 0; k < parameters.size(); ++k) {
    const std::string name = parameters[k]["name"].get<std::string>();
    EXPECT_TRUE(names_match(name, dataset.parameter_names[k])) << name << " in the place of " << dataset.parameter_names[k];
    scores.estimates.push_back(
        score(name, dataset.certified_estimates[k], parameters[k]["estimate"].get<double>()));
  }
  for (std::size_t k = 0; k < parameters.size(); ++k) {
    scores.deviations.push_back(score("sd(" + parameters[k]["name"].get<std::string>() + ")",
                                      dataset.certified_standard_deviations[k],
                                      parameters[k]["standard_error"].get<double>()));
  }
  scores.residual_sd = score("residual SD", dataset.certified_residual_sd, statistics["residual_sd"].get<double>());
  scores.r_squared = score("R-squared", dataset.certified_r_squared, statistics["r_squared"].get<double>());
  all_scores()[set] = scores;

  // The printed report tells the user how far to trust these numbers: its "digits lost" line is
  // fit.json's estimate, and it warns exactly when fewer than 4 digits are to be expected.
  const std::string report = read_text(work / "fit.txt");
  std::smatch lost;
  ASSERT_TRUE(std::regex_search(report, lost, std::regex(R"(about (\d+\.\d) digits lost)"))) << report;
  EXPECT_EQ(lost[1].str(), fmt::format("{:.1f}", scores.digits_lost));
  EXPECT_EQ(report.find("WARNING") != std::string::npos, 16 - scores.digits_lost < 4) << report;

  if (HasFailure()) {
    fmt::print("  kept {} for inspection\n", work.string());
  } else {
    std::error_code ignored;
    fs::remove_all(work, ignored);
  }
}

INSTANTIATE_TEST_SUITE_P(StRD, SidcBinaryNist, ::testing::ValuesIn(kSets),
                         [](const ::testing::TestParamInfo<std::string>& param) { return param.param; });

}  // namespace
