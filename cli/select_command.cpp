// `sidc select` (see select_command.hpp).
//
// Relies on: compiler/load_model.hpp, cli/record_options.hpp (the records and evaluation options,
// shared with sidc fit), driver/select_run.hpp (the selection, as the Python module makes it),
// report/fit_files.hpp (select.json).
// Guarantees: every bad option is a usage error (exit 2) naming the option, with did-you-mean for
// parameter names; a bad model or record is a user error (exit 1) rendered as sidc renders
// diagnostics; nothing is written unless --out is given, and then atomically.
#include "cli/select_command.hpp"

#include <filesystem>
#include <iostream>
#include <optional>

#include "cli/exit_codes.hpp"
#include "cli/number_check.hpp"
#include "cli/output_check.hpp"
#include "cli/progress_line.hpp"
#include "cli/record_options.hpp"
#include "compiler/load_model.hpp"
#include "diagnostics/cli_catalogue.hpp"
#include "distributed/session.hpp"
#include "driver/select_run.hpp"
#include "report/atomic_file.hpp"
#include "report/fit_files.hpp"

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
  std::size_t simulate_samples = 100000;   // per record, as sidc fit --validate-samples (every size is solved)
  std::string rule = "elbow";
  bool keep_drift = false;  // search drift absorbers of integrated equations too
  std::string out;
  std::optional<std::size_t> stream_above;  // --stream-above ENTRIES
};

int run_select(const SelectArguments& a) {
  if (auto problem = output_problem("--out", a.out, OutputKind::directory)) return fail(*problem, exit_code::user_error);
  std::string error, warnings;
  auto compiled = load_compiled_model(a.model, error, warnings);
  std::cerr << warnings;
  if (!compiled) return fail(error, exit_code::user_error);
  auto usage = [](const Diagnostic& d) { return fail(render(d), exit_code::usage_error); };

  driver::SelectSettings s;
  s.records = a.records.settings;
  s.method = a.method;
  s.rule = a.rule;
  s.required = a.required;
  s.dropped = a.dropped;
  s.folds = a.folds;
  s.bootstrap = a.bootstrap;
  s.seed = a.seed;
  s.max_size = a.max_size;
  s.simulate = a.simulate;
  s.simulate_samples = a.simulate_samples;
  s.keep_drift = a.keep_drift;
  // --group NAME=p1,p2,...: split here; what the names must be, the driver checks.
  for (const auto& spec : a.groups) {
    const auto eq = spec.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size()) return usage(cli_diag::bad_group(spec));
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
        group.second.push_back(item);
        item.clear();
      } else {
        item += ch;
      }
    }
    s.groups.push_back(std::move(group));
  }
  // Under mpirun: the streamed rows shared among the ranks, rank 0 alone printing and writing.
  distributed::Session& session = distributed::Session::current();
  s.share = session.row_share();
  s.records.share = s.share;  // each record read by byte ranges
  s.threads = session.threads_per_rank();
  s.stream_above = a.stream_above;
  s.processes = session.processes_line();
  ProgressLine progress;  // on stderr, only when it is a terminal
  auto prepared = driver::prepare_select(std::move(*compiled), a.model, fs::path(a.model).parent_path().string(), record_inputs(a.records), std::move(s),
                                         [&progress](const std::string& phase, std::size_t done, std::size_t total) { progress.update(phase, done, total); });
  if (auto* f = std::get_if<driver::Failure>(&prepared)) return fail(*f);
  driver::SelectRun& run = *std::get<std::unique_ptr<driver::SelectRun>>(prepared);
  if (!a.out.empty()) {  // before any work: select.json may not overwrite the model or a record
    std::vector<std::string> inputs{a.model};
    for (const auto& source : run.loaded.sources) inputs.push_back(source.path);
    if (const auto input = input_overwritten_by(select_file_path(a.out), inputs); !input.empty())
      return usage(cli_diag::output_is_input(select_file_path(a.out), input));
  }
  const driver::FitOutput print{[](const std::string& text) { std::cout << text; }, [](const std::string& line) { std::cerr << line << "\n"; }, {}};
  if (auto f = driver::run_select(run, print)) return fail(*f);
  // Every rank has selected, or the job stops here without a file written.
  if (!session.agree(exit_code::success)) return fail(render(diag::error("stopped", {}, session.who_left())), exit_code::user_error);
  if (!a.out.empty() && session.is_writer()) {
    auto written = write_select_file(a.out, *run.summary, a.model, run.options, run.settings.records.keep_outliers ? nullptr : &run.loaded.outliers);
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
  cmd->add_option("--simulate-samples", a->simulate_samples, "Samples of each record compared by --simulate at most (0 = all)")
      ->check(whole_number_check(0));
  cmd->add_option("--max-size", a->max_size, "Largest subset size reported")->check(CLI::Range(0, 10000));
  cmd->add_option("--rule", a->rule, "Criterion naming the non-contributory operations: elbow (default: the relative-G elbow, or CV's choice when smaller), cv, bic or aic")
      ->check(CLI::IsMember({"elbow", "aic", "bic", "cv"}));
  cmd->add_flag("--keep-drift", a->keep_drift, "Search candidates that are nearly a polynomial in t (drift absorbers) in integrated equations too");
  cmd->add_option("--out", a->out, "Directory for select.json");
  cmd->add_option("--stream-above", a->stream_above,
                  "Fold a record's rows into the time blocks' triangular factors block by block (memory that does not grow with the "
                  "record) when its design has more than this many entries, rows x candidates (default 8000000; 0 = always). "
                  "Under mpirun the ranks share the streamed rows (docs/distributed.md)")
      ->check(whole_number_check(0));
  cmd->callback([a, &exit_status] { exit_status = run_select(*a); });
}

}  // namespace sidc
