// `sidc select` (see select_command.hpp).
//
// Relies on: cli/fit_command.hpp (load_compiled_model), cli/record_options.hpp (the records and
// evaluation options, shared with sidc fit), runtime/select/select.hpp, runtime/simulate/validate.hpp (--simulate).
// Guarantees: every bad option is a usage error (exit 2) naming the option, with did-you-mean for
// parameter names; a bad model or record is a user error (exit 1) rendered as sidc renders
// diagnostics; nothing is written unless --out is given, and then atomically.
#include "cli/select_command.hpp"

#include "cli/record_options.hpp"

#include <cmath>
#include <filesystem>
#include <limits>
#include <iostream>
#include <map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cli/exit_codes.hpp"
#include "cli/fit_command.hpp"
#include "cli/read_file.hpp"
#include "report/atomic_file.hpp"
#include "ir/compiled_model.hpp"
#include "ir/settings.hpp"
#include "diagnostics/model_catalogue.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/records/records.hpp"
#include "runtime/select/select.hpp"
#include "runtime/simulate/validate.hpp"

namespace sidc {
namespace {

namespace fs = std::filesystem;

struct SelectArguments {
  std::string model;
  RecordArguments records;  // as sidc fit: --data, --from, --to, --every, ... (record_options.hpp)
  std::string method = "automatic";
  std::vector<std::string> required, groups, dropped;
  int folds = 5;
  int bootstrap = 0;
  std::uint64_t seed = 1;
  int max_size = -1;
  bool simulate = false;                   // rank the sizes by free-run simulation error too
  std::size_t simulate_samples = 100000;   // per record, as sidc fit --validate-samples
  std::string rule;  // empty: cv with cross-validation, bic with --folds 0
  std::string out;
};

// A usage error naming what is wrong, with did-you-mean among the model's parameters.
std::string unknown_parameter(const std::string& option, const std::string& name, const std::vector<std::string>& names) {
  std::string text = fmt::format("error: {} `{}`: the model has no parameter `{}`", option, name, name);
  const std::string near = diag::nearest(name, names);
  if (!near.empty()) return text + fmt::format("\nhint: did you mean `{}`?", near);
  std::string all;
  for (const auto& n : names) all += (all.empty() ? "" : ", ") + n;
  return text + "\nhint: the parameters are " + all;
}

nlohmann::ordered_json select_json(const SelectSummary& s, const std::string& model_path, const SelectOptions& o) {
  using nlohmann::ordered_json;
  ordered_json j;
  j["format"] = "sidc-select";
  j["version"] = 1;
  j["sidc_version"] = SIDC_VERSION;
  j["model"] = s.model_name;
  j["model_file"] = model_path;
  j["settings"] = {{"method", to_string(o.method)}, {"folds", o.folds}, {"bootstrap", o.bootstrap}, {"seed", o.seed},
                   {"max_size", o.max_size}, {"rule", to_string(o.rule)}, {"tolerance", o.tolerance},
                   {"required", o.required}, {"dropped", o.dropped}};
  ordered_json groups = ordered_json::array();
  for (const auto& g : s.groups) {
    ordered_json rows = ordered_json::array();
    for (const auto& r : g.rows) {
      ordered_json values = ordered_json::object();
      for (std::size_t k = 0; k < r.parameters.size(); ++k) values[r.parameters[k]] = r.values[k];
      rows.push_back({{"size", r.size}, {"parameters", values}, {"rank", r.rank}, {"G", r.G}, {"standard_error", r.standard_error},
                      {"aic", r.aic}, {"bic", r.bic}, {"cv", std::isfinite(r.cv) ? ordered_json(r.cv) : ordered_json(nullptr)},
                      {"cv_standard_error", std::isfinite(r.cv) ? ordered_json(r.cv_standard_error) : ordered_json(nullptr)},
                      {"simulation", r.simulation ? ordered_json(*r.simulation) : ordered_json(nullptr)}});
    }
    auto size_at = [&](int index) { return index < 0 ? ordered_json(nullptr) : ordered_json(g.rows[static_cast<std::size_t>(index)].size); };
    ordered_json operations = ordered_json::object();
    for (std::size_t c = 0; c < g.columns.size(); ++c) operations[g.columns[c]] = g.operations[c];
    ordered_json frequency = ordered_json::object();
    for (std::size_t c = 0; c < g.bootstrap_frequency.size(); ++c) frequency[g.columns[c]] = g.bootstrap_frequency[c];
    std::vector<std::size_t> equations;
    for (std::size_t e : g.equations) equations.push_back(e + 1);
    groups.push_back({{"equations", equations}, {"n", g.n}, {"operations", operations}, {"required", g.required}, {"dropped", g.dropped},
                      {"method", to_string(g.method)}, {"subsets_evaluated", g.nodes}, {"subsets_total", g.subsets_total},
                      {"search_seconds", g.search_seconds}, {"path", g.path}, {"sizes", rows},
                      {"best_size", {{"aic", size_at(g.best_aic)}, {"bic", size_at(g.best_bic)}, {"cv", size_at(g.best_cv)}, {"least_cv", size_at(g.least_cv)},
                                        {"simulation", size_at(g.best_simulation)}}},
                      {"chosen_size", size_at(g.chosen)}, {"non_contributory", g.non_contributory},
                      {"bootstrap", {{"replicates", g.bootstrap_replicates}, {"blocks", g.blocks}, {"frequency", frequency}}}});
  }
  j["groups"] = std::move(groups);
  return j;
}

int run_select(const SelectArguments& a) {
  std::string error;
  auto compiled = load_compiled_model(a.model, error);
  if (!compiled) {
    std::cerr << error << "\n";
    return exit_code::user_error;
  }
  const ir::Model& model = compiled->integrated;
  auto usage = [](const std::string& text) {
    std::cerr << text << "\n";
    return exit_code::usage_error;
  };

  // Options: the model's settings, overridden by the command line (as sidc fit).
  SelectOptions o;
  auto fit = fit_options(model, a.records, error);
  if (!fit) return usage(error);
  o.fit = *fit;
  const std::map<std::string, SelectionMethod> methods{
      {"automatic", SelectionMethod::automatic}, {"exact", SelectionMethod::exact}, {"stlsq", SelectionMethod::stlsq}, {"frols", SelectionMethod::frols}};
  o.method = methods.at(a.method);
  const std::string rule = !a.rule.empty() ? a.rule : a.folds >= 2 ? "cv" : "bic";
  o.rule = rule == "aic" ? SizeRule::aic : rule == "cv" ? SizeRule::cv : SizeRule::bic;
  o.folds = a.folds;
  o.bootstrap = a.bootstrap;
  o.seed = a.seed;
  o.max_size = a.max_size;

  // Names: every one must be a parameter of the model.
  const std::vector<std::string> names = selectable_parameters(model);
  auto known = [&](const std::string& n) { return std::find(names.begin(), names.end(), n) != names.end(); };
  for (const auto& n : a.required) {
    if (!known(n)) return usage(unknown_parameter("--require", n, names));
    o.required.push_back(n);
  }
  for (const auto& n : a.dropped) {
    if (!known(n)) return usage(unknown_parameter("--drop", n, names));
    if (std::find(a.required.begin(), a.required.end(), n) != a.required.end())
      return usage(fmt::format("error: `{}` is both required (--require) and dropped (--drop)", n));
    o.dropped.push_back(n);
  }
  std::map<std::string, std::string> group_of;
  for (const auto& spec : a.groups) {
    const auto eq = spec.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size())
      return usage(fmt::format("error: `--group {}` is not of the form NAME=p1,p2,...\nhint: e.g. `--group damper=c1[1],c1[2],c1[3]`", spec));
    std::pair<std::string, std::vector<std::string>> group{spec.substr(0, eq), {}};
    // Split on commas that are not inside brackets (c1[1..3] style names have none, but be safe).
    std::string item;
    int depth = 0;
    for (char ch : spec.substr(eq + 1) + ",") {
      if (ch == '[') ++depth;
      if (ch == ']') --depth;
      if (ch == ',' && depth == 0) {
        while (!item.empty() && item.front() == ' ') item.erase(item.begin());
        while (!item.empty() && item.back() == ' ') item.pop_back();
        if (item.empty()) return usage(fmt::format("error: `--group {}` has an empty parameter name", spec));
        if (!known(item)) return usage(unknown_parameter("--group " + group.first, item, names));
        if (auto [it, fresh] = group_of.emplace(item, group.first); !fresh)
          return usage(fmt::format("error: `{}` is in two groups, `{}` and `{}`", item, it->second, group.first));
        group.second.push_back(item);
        item.clear();
      } else {
        item += ch;
      }
    }
    o.groups.push_back(std::move(group));
  }
  if (!o.is_valid(&error)) return usage("error: " + error);

  auto loaded = load_records(*compiled, a.model, a.records, error);
  if (!loaded) {
    std::cerr << error << "\n";
    return exit_code::user_error;
  }
  const std::vector<SampledRecord>& records = loaded->records;

  // Section 2-4's test as a criterion: each size's best subset, solved from the record like the
  // validation of sidc fit, scored by its RMS error E[y] over outputs and records (divergence:
  // infinite). The derivative form is solved, so it needs every parameter of the equations: one
  // equation group only.
  std::optional<ExplicitForm> form;
  if (a.simulate) {
    if (equation_groups(model).size() != 1)
      return usage("error: --simulate ranks the subsets of one equation group, and this model has several\n"
                   "hint: select each group's operations from a model of that group alone");
    const auto& explicit_equations = *compiled->explicit_form;
    if (auto* d = std::get_if<Diagnostic>(&explicit_equations)) {
      std::cerr << render(*d) << "\nhint: --simulate needs equations that can be solved for their highest derivatives\n";
      return exit_code::user_error;
    }
    form = std::get<ExplicitForm>(explicit_equations);
    o.simulation_error = [&](std::size_t, const std::vector<std::string>& subset, const std::vector<double>& values) -> std::optional<double> {
      const ir::Model& derivative_form = compiled->normalized;
      std::vector<double> parameters(derivative_form.parameters.size(), 0.0);
      for (std::size_t i = 0; i < subset.size(); ++i)
        if (const int k = derivative_form.parameter_index(subset[i]); k >= 0) parameters[static_cast<std::size_t>(k)] = values[i];
      ValidationOptions v;
      v.derivative = o.fit.evaluation.derivative;
      v.max_samples = a.simulate_samples;
      double squares = 0;
      std::size_t count = 0;
      for (const auto& record : records) {
        auto run = validate(derivative_form, *form, parameters, record, v);
        if (!std::holds_alternative<ValidationSummary>(run)) return std::nullopt;
        const ValidationSummary& s = std::get<ValidationSummary>(run);
        if (!s.simulation.completed()) return std::numeric_limits<double>::infinity();
        for (const auto& out : s.outputs) squares += out.rms_error * out.rms_error * static_cast<double>(out.samples), count += out.samples;
      }
      return count ? std::sqrt(squares / static_cast<double>(count)) : std::optional<double>();
    };
  }

  auto result = select_operations(model, records, o);
  if (auto* d = std::get_if<Diagnostic>(&result)) {
    std::cerr << render(*d) << "\n";
    return exit_code::user_error;
  }
  const SelectSummary& summary = std::get<SelectSummary>(result);
  if (!summary.ok()) {
    std::cerr << "error: " << summary.message << "\n";
    return exit_code::user_error;
  }
  std::cout << fmt::format("sidc select: model `{}` ({}), size rule {}\n\n", model.name, a.model, to_string(o.rule)) << summary.report();
  if (!a.out.empty()) {
    std::error_code ec;
    fs::create_directories(a.out, ec);
    const std::string path = (fs::path(a.out) / "select.json").string();
    if (ec || !write_file_atomically(path, select_json(summary, a.model, o).dump(1) + "\n", &error)) {
      std::cerr << (error.empty() ? fmt::format("error: cannot create `{}`: {}", a.out, ec.message()) : "error: " + error) << "\n";
      return exit_code::user_error;
    }
    std::cerr << "wrote " << path << "\n";
  }
  return exit_code::success;
}

}  // namespace

void add_select_command(CLI::App& app, int& exit_status) {
  auto a = std::make_shared<SelectArguments>();
  CLI::App* cmd = app.add_subcommand("select", "Determine which operations contribute: best subset per size, AIC, BIC, CV (thesis section 2-3)");
  cmd->add_option("model", a->model, "Model file (.sid) or compiled model (.sidc.json) with every candidate operation")->required();
  add_record_options(cmd, a->records);
  cmd->add_option("--method", a->method, "exact (branch and bound), stlsq, frols, or automatic (exact up to 26 free candidates, else frols)")
      ->check(CLI::IsMember({"automatic", "exact", "stlsq", "frols"}));
  cmd->add_option("--require", a->required, "A parameter kept in every subset (repeatable)");
  cmd->add_option("--group", a->groups, "NAME=p1,p2,...: parameters that enter or leave together (repeatable)");
  cmd->add_option("--drop", a->dropped, "A parameter removed before the search (repeatable)");
  cmd->add_option("--folds", a->folds, "K for cross-validation over K contiguous time blocks (0 = off)")->check(CLI::Range(0, 1000));
  cmd->add_option("--bootstrap", a->bootstrap, "Bootstrap replicates over time blocks (0 = off)")->check(CLI::Range(0, 100000));
  cmd->add_option("--seed", a->seed, "Seed of the bootstrap's random draws");
  cmd->add_flag("--simulate", a->simulate, "Also rank the sizes by the RMS error of the best subset's solution against the record (thesis section 2-4)");
  cmd->add_option("--simulate-samples", a->simulate_samples, "Samples of each record compared by --simulate at most (0 = all)");
  cmd->add_option("--max-size", a->max_size, "Largest subset size reported")->check(CLI::Range(0, 10000));
  cmd->add_option("--rule", a->rule, "Criterion naming the non-contributory operations: cv (default), bic (default with --folds 0) or aic")->check(CLI::IsMember({"aic", "bic", "cv"}));
  cmd->add_option("--out", a->out, "Directory for select.json");
  cmd->callback([a, &exit_status] { exit_status = run_select(*a); });
}

}  // namespace sidc
