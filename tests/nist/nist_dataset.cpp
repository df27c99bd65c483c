// NIST StRD reader and designs (see nist_dataset.hpp).
#include "nist_dataset.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

#include <fmt/format.h>

namespace sidc::nist {
namespace {

std::vector<std::string> tokens_of(const std::string& line) {
  std::istringstream stream(line);
  std::vector<std::string> tokens;
  std::string token;
  while (stream >> token) tokens.push_back(token);
  return tokens;
}

// strtod reads every Fortran-style number in these files (E exponents, "760.", ".11019").
bool parse_number(const std::string& text, double& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(value);
}

bool line_range(const std::string& line, int& first, int& last) {
  static const std::regex pattern(R"(\(lines\s+(\d+)\s+to\s+(\d+)\))");
  std::smatch match;
  if (!std::regex_search(line, match, pattern)) return false;
  first = std::stoi(match[1].str());
  last = std::stoi(match[2].str());
  return true;
}

}  // namespace

Dataset read_dataset(const std::string& path) {
  Dataset dataset;
  const std::size_t slash = path.find_last_of('/');
  dataset.name = path.substr(slash == std::string::npos ? 0 : slash + 1);
  if (dataset.name.size() > 4 && dataset.name.ends_with(".dat")) dataset.name.resize(dataset.name.size() - 4);

  std::ifstream file(path);
  if (!file) {
    dataset.error = "cannot open " + path;
    return dataset;
  }
  std::vector<std::string> lines;
  for (std::string line; std::getline(file, line);) lines.push_back(line);

  int certified_first = 0, certified_last = 0, data_first = 0, data_last = 0;
  for (const std::string& line : lines) {
    if (line.find("Certified Values") != std::string::npos) line_range(line, certified_first, certified_last);
    if (line.find("Data ") != std::string::npos && line.find("(lines") != std::string::npos) {
      line_range(line, data_first, data_last);
    }
  }
  const int count = static_cast<int>(lines.size());
  if (certified_first < 1 || certified_last > count || data_first < 1 || data_last > count) {
    dataset.error = "header has no usable 'Certified Values (lines A to B)' / 'Data (lines C to D)'";
    return dataset;
  }

  bool residual_sd_found = false, r_squared_found = false;
  for (int number = certified_first; number <= certified_last; ++number) {
    const std::string& line = lines[static_cast<std::size_t>(number - 1)];
    const std::vector<std::string> tokens = tokens_of(line);
    if (tokens.empty()) continue;
    double estimate = 0, deviation = 0;
    if (std::regex_match(tokens[0], std::regex("B[0-9]+")) && tokens.size() == 3 &&
        parse_number(tokens[1], estimate) && parse_number(tokens[2], deviation)) {
      dataset.parameter_names.push_back(tokens[0]);
      dataset.certified_estimates.push_back(estimate);
      dataset.certified_standard_deviations.push_back(deviation);
    } else if (line.find("Standard Deviation") != std::string::npos && parse_number(tokens.back(), estimate)) {
      dataset.certified_residual_sd = estimate;
      residual_sd_found = true;
    } else if (tokens[0] == "R-Squared" && tokens.size() == 2 && parse_number(tokens[1], estimate)) {
      dataset.certified_r_squared = estimate;
      r_squared_found = true;
    }
  }
  if (dataset.parameter_names.empty() || !residual_sd_found || !r_squared_found) {
    dataset.error = "certified block lacks parameters, residual SD or R-Squared";
    return dataset;
  }

  for (int number = data_first; number <= data_last; ++number) {
    const std::vector<std::string> tokens = tokens_of(lines[static_cast<std::size_t>(number - 1)]);
    if (tokens.empty()) continue;
    std::vector<double> values;
    for (const std::string& token : tokens) {
      double value = 0;
      if (!parse_number(token, value)) {
        dataset.error = fmt::format("line {}: '{}' is not a number", number, token);
        return dataset;
      }
      values.push_back(value);
    }
    if (values.size() < 2 || (!dataset.x.empty() && values.size() != dataset.x.front().size() + 1)) {
      dataset.error = fmt::format("line {} has the wrong number of columns", number);
      return dataset;
    }
    dataset.y.push_back(values.front());
    dataset.x.emplace_back(values.begin() + 1, values.end());
  }
  if (dataset.y.empty()) dataset.error = "no data rows";
  return dataset;
}

bool build_design(const Dataset& dataset, Design& design, std::string* why) {
  const auto fail = [&](const std::string& text) {
    if (why) *why = dataset.name + ": " + text;
    return false;
  };
  if (!dataset.error.empty()) return fail(dataset.error);
  const auto n = static_cast<Eigen::Index>(dataset.y.size());
  const auto p = static_cast<Eigen::Index>(dataset.parameter_names.size());
  const std::size_t predictors = dataset.x.front().size();
  const bool intercept = dataset.parameter_names.front() == "B0";
  design.A.resize(n, p);
  design.b = Eigen::Map<const Eigen::VectorXd>(dataset.y.data(), n);
  design.names = dataset.parameter_names;
  if (predictors == 1) {
    // Polynomial in x; column k holds x^(k + first power). std::pow is what an expression
    // evaluator does for x**k; it is within an ulp of the exact power.
    const int first_power = intercept ? 0 : 1;
    if (!intercept && p != 1) return fail("no-intercept model with more than one parameter");
    for (Eigen::Index i = 0; i < n; ++i) {
      const double x = dataset.x[static_cast<std::size_t>(i)][0];
      for (Eigen::Index k = 0; k < p; ++k) {
        const int power = static_cast<int>(k) + first_power;
        design.A(i, k) = power == 0 ? 1.0 : power == 1 ? x : std::pow(x, power);
      }
    }
    return true;
  }
  if (!intercept || static_cast<std::size_t>(p) != predictors + 1) {
    return fail("several predictors need B0..Bq with q = number of predictors");
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    design.A(i, 0) = 1.0;
    for (std::size_t k = 0; k < predictors; ++k) {
      design.A(i, static_cast<Eigen::Index>(k) + 1) = dataset.x[static_cast<std::size_t>(i)][k];
    }
  }
  return true;
}

double log_relative_error(double estimate, double certified) {
  if (!std::isfinite(estimate)) return 0;
  const double error = certified == 0 ? std::abs(estimate) : std::abs(estimate - certified) / std::abs(certified);
  if (error == 0) return 15;
  return std::clamp(-std::log10(error), 0.0, 15.0);
}

}  // namespace sidc::nist
