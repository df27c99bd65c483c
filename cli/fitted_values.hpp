// The parameter values a fit.json stands by, read back for `sidc simulate --params` and
// `sidc export`: the equation-error estimates, replaced by the instrumental-variable ones when that
// iteration converged, replaced by the output-error ones when refinement did not fail (the last
// estimate a fit made is its answer; docs/cli.md).
//
// Relies on: the fit.json format of report/fit_files.cpp (`format` "sidc-fit"). Guarantees: names
// in the order met, a later estimate of a name after an earlier one; an estimate written as a
// non-finite string ("nan") is left out. Nullopt when `j` is not a fit.json.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sidc {

std::optional<std::vector<std::pair<std::string, double>>> fitted_values(const nlohmann::json& j);

}  // namespace sidc
