#include "cli/record_options.hpp"

#include <cmath>

#include "cli/number_check.hpp"

namespace sidc {
namespace {

const CLI::Validator positive =
    number_check("POSITIVE", [](double x) { return x > 0 && std::isfinite(x); }, "`{}` is not a positive number");

}  // namespace

void add_record_options(CLI::App* cmd, RecordArguments& a) {
  driver::RecordSettings& s = a.settings;
  // One file per --data: a word after it is never taken as a record (`--data a.csv model.sid`).
  cmd->add_option("--data", a.data, "A record to use instead of the model's data statements (CSV); repeat it for several: --data a.csv --data b.csv")
      ->allow_extra_args(false);
  cmd->add_option("--from", s.from, "Start of the fit window (time)");
  cmd->add_option("--to", s.to, "End of the fit window (time)");
  cmd->add_option("--every", s.every, "Keep every K-th sample")->check(positive);
  cmd->add_option("--step", s.step, "Sampling step, for records without a time column")->check(positive);
  cmd->add_option("--resample", s.resample, "Interpolate the record linearly onto this uniform step")->check(positive);
  cmd->add_option("--derivative", s.derivative, "Moving-arc operator, e.g. \"savgol(7, 3)\"");
  cmd->add_option("--second-derivative", s.second_derivative, "repeated (eq. 3-1.8) or direct")->check(CLI::IsMember({"repeated", "direct"}));
  cmd->add_option("--edges", s.edges, "drop (the thesis) or shorten")->check(CLI::IsMember({"drop", "shorten"}));
  cmd->add_option("--integration", s.integration, "simpson or trapezoid")->check(CLI::IsMember({"simpson", "trapezoid"}));
  cmd->add_option("--precision", s.precision, "Least-squares arithmetic: automatic, double or extended")
      ->check(CLI::IsMember({"automatic", "double", "extended"}));
  cmd->add_option("--weights", s.weights, "A record column weighting each row's residual (eq. 2-1.6)");
  cmd->add_flag("--split-at-gaps", s.split_at_gaps,
                "Cut each record at its gaps (missing samples, faulty cells) and fit the stretches as separate records");
  cmd->add_flag("--keep-outliers", s.keep_outliers,
                "Keep the outputs' isolated outliers (default: replaced by their neighbours' value, and reported)");
}

std::vector<driver::RecordInput> record_inputs(const RecordArguments& a) { return {a.data.begin(), a.data.end()}; }

}  // namespace sidc
