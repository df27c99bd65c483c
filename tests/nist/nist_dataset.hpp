// Reader for the NIST StRD linear least-squares files (tests/nist/data/*.dat, copied byte for byte
// from /work/shared/data/nist-strd; see its README.md) and the design matrix of each model.
//
// Relies on the layout NIST gives in each header: "Certified Values (lines A to B)" and
// "Data (lines C to D)". Certified lines are `Bk estimate sd`, then "Standard Deviation <value>"
// (residual SD) and "R-Squared <value>"; numbers are Fortran style (0.4E-03, 760., .11019).
// Data lines C..D are read, blank lines skipped; the first column is y.
// Guarantees: never throws; a malformed file comes back with `error` set.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace sidc::nist {

struct Dataset {
  std::string name;   // file name without .dat
  std::string error;  // empty when the file was read completely
  std::vector<std::string> parameter_names;  // B0.. or B1.. as certified
  std::vector<double> certified_estimates;
  std::vector<double> certified_standard_deviations;
  double certified_residual_sd = 0;
  double certified_r_squared = 0;
  std::vector<double> y;
  std::vector<std::vector<double>> x;  // per row, the predictor columns after y
};

Dataset read_dataset(const std::string& path);

// The model of each StRD linear set, from its certified parameter names and predictor count:
// one predictor and B0..Bk: polynomial of degree k (columns 1, x, x^2 = std::pow(x, 2), ...);
// one predictor and B1 only: y = B1 x (NoInt1/2, no intercept); several predictors and B0..Bq:
// linear in them with an intercept (Longley). Returns false (with why) for anything else.
struct Design {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  std::vector<std::string> names;
};
bool build_design(const Dataset& dataset, Design& design, std::string* why);

// Log relative error (McCullough 1998): -log10(|estimate - certified| / |certified|), or
// -log10(|estimate|) when the certified value is 0; capped at 15 (what 15 printed digits support),
// floored at 0; NaN scores 0.
double log_relative_error(double estimate, double certified);

}  // namespace sidc::nist
