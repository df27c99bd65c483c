// `sidc select` (see select_command.hpp).
//
// Relies on: compiler/load_model.hpp, cli/record_options.hpp (the records and evaluation options,
// shared with sidc fit), runtime/select/select.hpp, runtime/simulate/validate.hpp (--simulate),
// report/fit_files.hpp (select.json).
// Guarantees: every bad option is a usage error (exit 2) naming the option, with did-you-mean for
// parameter names; a bad model or record is a user error (exit 1) rendered as sidc renders
// diagnostics; nothing is written unless --out is given, and then atomically.
#include "cli/select_command.hpp"

#include <filesystem>
#include <iostream>
#include <map>

#include <fmt/format.h>

#include "cli/exit_codes.hpp"
#include "cli/output_check.hpp"
#include "cli/record_options.hpp"
#include "compiler/load_model.hpp"
#include "compiler/pipeline.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "report/atomic_file.hpp"
#include "report/fit_files.hpp"
#include "runtime/select/select.hpp"
#include "runtime/simulate/validate.hpp"

namespace sidc {
namespace {

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
  std::string rule = "elbow";
  bool keep_drift = false;  // search drift absorbers of integrated equations too
  std::string out;
};

int run_select(const SelectArguments& a) {
  if (auto problem = output_problem("--out", a.out, OutputKind::directory)) return fail(*problem, exit_code::user_error);
  std::string error, warnings;
  auto compiled = load_compiled_model(a.model, error, warnings);
  std::cerr << warnings;
  if (!compiled) return fail(error, exit_code::user_error);
  // The model names no form: the weak form, with which selection found the true terms of every
  // known-truth record of docs/accuracy.md up to 1% noise (the candidates change with the subset,
  // so sidc fit's choice by simulation has nothing fixed to compare here).
  const bool weak_by_default = compiled->integrated.form_from_data;
  if (weak_by_default) compiled->integrated = rewritten_in_form(compiled->normalized, "weak");
  const ir::Model& model = compiled->integrated;
  auto usage = [](const Diagnostic& d) { return fail(render(d), exit_code::usage_error); };

  // Options: the model's settings, overridden by the command line (as sidc fit).
  SelectOptions o;
  auto fit = fit_options(model, a.records, error);
  if (!fit) return fail(error, exit_code::usage_error);
  o.fit = *fit;
  const std::map<std::string, SelectionMethod> methods{
      {"automatic", SelectionMethod::automatic}, {"exact", SelectionMethod::exact}, {"stlsq", SelectionMethod::stlsq}, {"frols", SelectionMethod::frols}};
  o.method = methods.at(a.method);
  const std::map<std::string, SizeRule> rules{{"aic", SizeRule::aic}, {"bic", SizeRule::bic}, {"cv", SizeRule::cv}, {"elbow", SizeRule::elbow}};
  o.rule = rules.at(a.rule);
  o.keep_drift = a.keep_drift;
  o.folds = a.folds;
  o.bootstrap = a.bootstrap;
  o.seed = a.seed;
  o.max_size = a.max_size;

  // Names: every one must be a parameter of the model.
  const std::vector<std::string> names = selectable_parameters(model);
  auto known = [&](const std::string& n) { return std::find(names.begin(), names.end(), n) != names.end(); };
  for (const auto& n : a.required) {
    if (!known(n)) return usage(cli_diag::unknown_parameter("--require", n, names));
    o.required.push_back(n);
  }
  for (const auto& n : a.dropped) {
    if (!known(n)) return usage(cli_diag::unknown_parameter("--drop", n, names));
    if (std::find(a.required.begin(), a.required.end(), n) != a.required.end())
      return usage(cli_diag::required_and_dropped(n));
    o.dropped.push_back(n);
  }
  std::map<std::string, std::string> group_of;
  for (const auto& spec : a.groups) {
    const auto eq = spec.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size())
      return usage(cli_diag::bad_group(spec));
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
        if (item.empty()) return usage(cli_diag::empty_group_member(spec));
        if (!known(item)) return usage(cli_diag::unknown_parameter("--group " + group.first, item, names));
        if (auto [it, fresh] = group_of.emplace(item, group.first); !fresh)
          return usage(cli_diag::in_two_groups(item, it->second, group.first));
        group.second.push_back(item);
        item.clear();
      } else {
        item += ch;
      }
    }
    o.groups.push_back(std::move(group));
  }
  if (!o.is_valid(&error)) return usage(cli_diag::invalid_options(error));

  auto loaded = load_records(*compiled, a.model, a.records, error);
  if (!loaded) return fail(error, exit_code::user_error);
  if (!a.out.empty()) {  // before any work: select.json may not overwrite the model or a record
    std::vector<std::string> inputs{a.model};
    for (const auto& s : loaded->sources) inputs.push_back(s.path);
    if (const auto input = input_overwritten_by(select_file_path(a.out), inputs); !input.empty())
      return usage(cli_diag::output_is_input(select_file_path(a.out), input));
  }
  const std::vector<SampledRecord>& records = loaded->records;

  // Section 2-4's test as a criterion: each size's best subset, solved from the record like the
  // validation of sidc fit, scored by its RMS error E[y] over outputs and records (divergence:
  // infinite). The derivative form is solved, so it needs every parameter of the equations: one
  // equation group only.
  if (a.simulate) {
    if (equation_groups(model).size() != 1) return usage(cli_diag::simulate_needs_one_group());
    if (auto* d = std::get_if<Diagnostic>(&*compiled->explicit_form))
      return fail(render(cli_diag::simulate_needs_explicit_form(*d)), exit_code::user_error);
    o.simulation_error = [&](std::size_t, const std::vector<ParameterIndex>& subset, const std::vector<double>& values) {
      return simulation_rms_error(compiled->normalized, std::get<ExplicitForm>(*compiled->explicit_form), subset, values, records,
                                  o.fit.evaluation, a.simulate_samples);
    };
  }

  auto result = select_operations(model, records, o);
  std::string form_note = weak_by_default ? "form: weak (the model sets none; `set form` chooses another)\n" : "";
  if (auto* d = std::get_if<Diagnostic>(&result); d && weak_by_default && d->code == "weak-form-too-short") {
    // A record too short for the weak form's subdomains (the 115 samples of thesis section 4-2):
    // the integrated form needs no margin, and is what sidc fit's form choice falls back to there.
    form_note = fmt::format("form: integrated (the model sets none, and the weak form cannot be built: {})\n", d->message);
    compiled->integrated = rewritten_in_form(compiled->normalized, "integrated");
    result = select_operations(model, records, o);
  }
  if (auto* d = std::get_if<Diagnostic>(&result)) return fail(render(*d), exit_code::user_error);
  const SelectSummary& summary = std::get<SelectSummary>(result);
  if (!summary.ok()) return fail(render(cli_diag::selection_failed(summary.message)), exit_code::user_error);
  // Drift absorbers are warnings: on stderr too, where a script looks for them.
  for (const auto& g : summary.groups)
    for (const auto& d : g.drift)
      std::cerr << fmt::format("{}: warning: `{}` is nearly a polynomial in t of degree {} over the window (before integration, a + b t holds {:.4f}% of it): a drift absorber{}\n",
                               a.model, d.column, d.degree, 100 * d.share,
                               d.set_aside ? "; set aside before the search (give --keep-drift or --require to search it)" : "");
  std::cout << fmt::format("sidc select: model `{}` ({}), size rule {}\n{}\n", model.name, a.model, to_string(o.rule), form_note)
            << summary.report();
  if (!a.out.empty()) {
    auto written = write_select_file(a.out, summary, a.model, o);
    if (auto* d = std::get_if<Diagnostic>(&written)) return fail(render(*d), exit_code::user_error);
    std::cerr << "wrote " << std::get<std::string>(written) << "\n";
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
  // One value per occurrence (or several, comma-separated): a word after it is never taken as a value.
  cmd->add_option("--require", a->required, "Parameters kept in every subset (repeatable or comma-separated)")->allow_extra_args(false)->delimiter(',');
  cmd->add_option("--group", a->groups, "NAME=p1,p2,...: parameters that enter or leave together (repeatable)")->allow_extra_args(false);
  cmd->add_option("--drop", a->dropped, "Parameters removed before the search (repeatable or comma-separated)")->allow_extra_args(false)->delimiter(',');
  cmd->add_option("--folds", a->folds, "K for cross-validation over K contiguous time blocks (0 = off)")->check(CLI::Range(0, 1000));
  cmd->add_option("--bootstrap", a->bootstrap, "Bootstrap replicates over time blocks (0 = off)")->check(CLI::Range(0, 100000));
  cmd->add_option("--seed", a->seed, "Seed of the bootstrap's random draws");
  cmd->add_flag("--simulate", a->simulate, "Also rank the sizes by the RMS error of the best subset's solution against the record (thesis section 2-4)");
  cmd->add_option("--simulate-samples", a->simulate_samples, "Samples of each record compared by --simulate at most (0 = all)");
  cmd->add_option("--max-size", a->max_size, "Largest subset size reported")->check(CLI::Range(0, 10000));
  cmd->add_option("--rule", a->rule, "Criterion naming the non-contributory operations: elbow (default: the relative-G elbow, or CV's choice when smaller), cv, bic or aic")
      ->check(CLI::IsMember({"elbow", "aic", "bic", "cv"}));
  cmd->add_flag("--keep-drift", a->keep_drift, "Search candidates that are nearly a polynomial in t (drift absorbers) in integrated equations too");
  cmd->add_option("--out", a->out, "Directory for select.json");
  cmd->callback([a, &exit_status] { exit_status = run_select(*a); });
}

}  // namespace sidc
