// fit_bench: how fast, and in how much memory, sidc fits a second-order model with 20 candidate
// operations to a long record (10^7 rows by default), phase by phase. Not a test: run it by hand
// (bench/README.md gives the command and the measured baseline).
//
// Relies on: the sidc libraries (grammar, compiler, runtime) for the in-process phases, and the
// `sidc` binary (its path is the compile definition SIDC_BINARY) for the command-line path.
// Guarantees:
// - The record is a forced Duffing-van der Pol oscillator, m y'' + c1 y' + c3 y'^3 + s1 y + s3 y^3
//   + d2 y^2 y' = x(t), integrated by classical RK4 in this file with the sampling step, so the
//   model holds up to the derivative estimates' error; the fitted values of the true terms are
//   printed next to the truth, so a fast but wrong fit shows.
// - In-process phases (compile, parse, bind, fit) call the same library functions as `sidc fit`;
//   fit() splits its own time into evaluation, folding and the final solve; each reports wall time, rows per
//   second, CPU time / wall time (how many cores were busy), resident memory after the phase and
//   the process's peak so far (getrusage ru_maxrss, a high-water mark: it never goes down).
// - The command-line path `sidc compile && sidc fit` runs as child processes, before the
//   in-process phases; their peak memory comes from wait4()'s rusage, so it is the child's own
//   (plus at most this process's resident size at the fork, printed: a few MB).
// - PASS/FAIL is judged against the targets: the whole fit, CSV to report, in under 3 s,
//   with peak memory under 1 GB (10^9 bytes). MB here is always 10^6 bytes.
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <variant>
#include <vector>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include "compiler/pipeline.hpp"
#include "ir/settings.hpp"
#include "runtime/records/bind_record.hpp"
#include "runtime/operators/evaluate.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/solve/least_squares.hpp"
#include "runtime/solve/options_from_settings.hpp"
#include "runtime/records/records.hpp"

#ifndef SIDC_BINARY
#define SIDC_BINARY "sidc"
#endif

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr double kTargetSeconds = 3.0;
constexpr double kTargetPeakMB = 1000.0;  // 1 GB = 10^9 bytes

struct BenchOptions {
  std::size_t rows = 10'000'000;
  bool keep = false;          // keep the CSV after the run, and reuse it when it is already there
  std::string dir = "/tmp/sidc-bench";
  bool library = true;        // the in-process phases
  bool command_line = true;   // `sidc compile && sidc fit` as child processes
  std::size_t block_rows = 0; // 0: FitOptions' default
  int threads = 0;            // 0: FitOptions' default (one per core)
};

void print_usage() {
  std::cout << "usage: fit_bench [--rows N] [--keep] [--dir PATH] [--skip-library] [--skip-cli]\n"
               "  --rows N        rows of the generated record (default 10000000; 1e7 is accepted)\n"
               "  --keep          keep the generated CSV (and reuse it if it exists) instead of deleting it\n"
               "  --dir PATH      where the CSV, the model and the fit report go (default /tmp/sidc-bench)\n"
               "  --skip-library  do not run the in-process phases\n"
               "  --skip-cli      do not run `sidc compile && sidc fit` as child processes\n"
               "  --block-rows N  in-process fit: rows per streamed block (default: FitOptions' 2048)\n"
               "  --threads N     in-process fit: threads folding blocks (default: one per core)\n";
}

std::optional<BenchOptions> parse_arguments(int argc, char** argv) {
  BenchOptions o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--rows" && i + 1 < argc) {
      // Accepts 10000000 as well as 1e7.
      char* end = nullptr;
      const double v = std::strtod(argv[++i], &end);
      if (*end != '\0' || !(v >= 100) || v > 1e10 || v != std::floor(v)) {
        std::cerr << "fit_bench: --rows takes a whole number of at least 100\n";
        return std::nullopt;
      }
      o.rows = static_cast<std::size_t>(v);
    } else if (a == "--keep") {
      o.keep = true;
    } else if (a == "--dir" && i + 1 < argc) {
      o.dir = argv[++i];
    } else if (a == "--skip-library") {
      o.library = false;
    } else if (a == "--skip-cli") {
      o.command_line = false;
    } else if (a == "--block-rows" && i + 1 < argc) {
      o.block_rows = static_cast<std::size_t>(std::max(1L, std::strtol(argv[++i], nullptr, 10)));
    } else if (a == "--threads" && i + 1 < argc) {
      o.threads = static_cast<int>(std::max(1L, std::strtol(argv[++i], nullptr, 10)));
    } else {
      print_usage();
      return std::nullopt;
    }
  }
  return o;
}

// ---- the record ---------------------------------------------------------------------------------

// The true system. Its 6 non-zero coefficients are among the model's 20 candidates.
struct Oscillator {
  double m = 1.0, c1 = 0.3, c3 = 0.05, s1 = 1.0, s3 = 0.5, d2 = 0.2;
  static double force(double t) { return 1.5 * std::sin(0.7 * t) + 0.8 * std::sin(1.9 * t + 0.3) + 0.4 * std::sin(3.7 * t); }
  // y'' from m y'' + c1 y' + c3 y'^3 + s1 y + s3 y^3 + d2 y^2 y' = x(t).
  double acceleration(double t, double y, double v) const {
    return (force(t) - c1 * v - c3 * v * v * v - s1 * y - s3 * y * y * y - d2 * y * y * v) / m;
  }
};

constexpr double kStep = 1e-3;  // sampling step (s); 10^7 rows span 10^4 s, about 1600 periods

// Writes t, x, y with 12 significant digits (a rounding of 1e-12 costs y'' about 1e-6 relative
// through the moving arc at this step). Written to a temporary name and renamed, so an interrupted
// run never leaves a short file that --keep would reuse.
bool write_record(const fs::path& path, std::size_t rows, std::string& error) {
  const fs::path partial = path.string() + ".partial";
  std::FILE* out = std::fopen(partial.c_str(), "wb");
  if (!out) {
    error = fmt::format("cannot write {}: {}", partial.string(), std::strerror(errno));
    return false;
  }
  const Oscillator sys;
  std::vector<char> buffer(1 << 20);
  std::size_t used = 0;
  auto put = [&](std::string_view s) {
    std::memcpy(buffer.data() + used, s.data(), s.size());
    used += s.size();
  };
  auto put_number = [&](double v, char after) {
    auto [end, ec] = std::to_chars(buffer.data() + used, buffer.data() + buffer.size(), v, std::chars_format::general, 12);
    used = static_cast<std::size_t>(end - buffer.data());
    buffer[used++] = after;
  };
  put("t,x,y\n");
  double y = 0, v = 0;
  bool ok = true;
  for (std::size_t k = 0; k < rows && ok; ++k) {
    const double t = static_cast<double>(k) * kStep;
    put_number(t, ',');
    put_number(Oscillator::force(t), ',');
    put_number(y, '\n');
    // Classical RK4 for (y, v) over one step.
    const double h = kStep;
    const double k1y = v, k1v = sys.acceleration(t, y, v);
    const double k2y = v + 0.5 * h * k1v, k2v = sys.acceleration(t + 0.5 * h, y + 0.5 * h * k1y, v + 0.5 * h * k1v);
    const double k3y = v + 0.5 * h * k2v, k3v = sys.acceleration(t + 0.5 * h, y + 0.5 * h * k2y, v + 0.5 * h * k2v);
    const double k4y = v + h * k3v, k4v = sys.acceleration(t + h, y + h * k3y, v + h * k3v);
    y += h / 6 * (k1y + 2 * k2y + 2 * k3y + k4y);
    v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    if (buffer.size() - used < 256) {
      ok = std::fwrite(buffer.data(), 1, used, out) == used;
      used = 0;
    }
  }
  ok = ok && std::fwrite(buffer.data(), 1, used, out) == used;
  ok = (std::fclose(out) == 0) && ok;
  if (!ok) {
    error = fmt::format("cannot write {} (disk full?)", partial.string());
    fs::remove(partial);
    return false;
  }
  fs::rename(partial, path);
  return true;
}

// 20 candidate operations of a second-order model in derivative form (y'' estimated by the
// 7-point cubic moving arc applied twice, eq. 3-1.8): the inertia, polynomial damping and
// stiffness up to degree 6, and seven mixed terms y^k y'.
std::string model_text(const std::string& csv_name) {
  return fmt::format(
      "# fit_bench: 20 candidate operations of a second-order system (written by bench/fit_bench.cpp)\n"
      "model fit_bench\n"
      "input  x\n"
      "output y\n"
      "param  m, c[1..6], s[1..6], d[1..7]\n"
      "\n"
      "data \"{}\" (t = \"t\", x = \"x\", y = \"y\")\n"
      "set derivative = savgol(7, 3)\n"
      "set integrate = 0\n"
      "\n"
      "m*y'' + sum(k = 1..6, c[k]*y'^k) + sum(k = 1..6, s[k]*y^k) + sum(k = 1..7, d[k]*y^k*y') = x\n",
      csv_name);
}

// ---- measurement --------------------------------------------------------------------------------

double seconds_of(const timeval& tv) { return static_cast<double>(tv.tv_sec) + 1e-6 * static_cast<double>(tv.tv_usec); }

struct CpuTime {
  double user = 0, system = 0;
};

CpuTime cpu_time_self() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return {seconds_of(u.ru_utime), seconds_of(u.ru_stime)};
}

// Other processes on the machine slow every phase down; the load average says whether they did.
std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  if (!(in >> one >> five >> fifteen)) return "unknown";
  return fmt::format("{} {} {} (1, 5, 15 min)", one, five, fifteen);
}

double peak_mb_self() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) * 1024.0 / 1e6;  // ru_maxrss is in KiB on Linux
}

double resident_mb_self() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  if (!(statm >> size >> resident)) return NAN;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1e6;
}

struct Phase {
  std::string name;
  double seconds = 0;
  double rows = 0;       // rows handled (0: no rate)
  double megabytes = 0;  // bytes handled / 10^6 (0: no rate)
  double cpu_seconds = 0;     // user + system, all threads
  double system_seconds = 0;  // of which in the kernel (page faults of fresh allocations, mostly)
  double resident_mb = NAN;  // after the phase
  double peak_mb = NAN;      // the process's peak so far (or the child's peak)
  bool counts_to_total = true;
};

std::vector<Phase> phases;

// Runs `work` and records it as a phase. `work` returns false to stop the benchmark.
bool measure(const std::string& name, double rows, const std::function<bool()>& work, double megabytes = 0,
             bool counts_to_total = true) {
  std::cout << fmt::format("  {:<40}", name) << std::flush;
  const CpuTime cpu0 = cpu_time_self();
  const auto t0 = Clock::now();
  const bool ok = work();
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  const CpuTime cpu1 = cpu_time_self();
  Phase p{name,
          seconds,
          rows,
          megabytes,
          cpu1.user + cpu1.system - cpu0.user - cpu0.system,
          cpu1.system - cpu0.system,
          resident_mb_self(),
          peak_mb_self(),
          counts_to_total};
  std::cout << fmt::format("{:8.3f} s   peak {:8.1f} MB\n", p.seconds, p.peak_mb);
  phases.push_back(p);
  return ok;
}

std::string rate(double count, double seconds) {
  if (count <= 0 || seconds <= 0) return "";
  const double r = count / seconds;
  if (r >= 1e6) return fmt::format("{:.2f} M", r / 1e6);
  if (r >= 1e3) return fmt::format("{:.1f} k", r / 1e3);
  return fmt::format("{:.0f}", r);
}

void print_table(const std::string& title) {
  std::cout << "\n" << title << "\n";
  std::cout << fmt::format("  {:<40} {:>9} {:>11} {:>9} {:>8} {:>6} {:>10} {:>10}\n", "phase", "seconds", "rows/s", "MB/s", "cpu/wall",
                           "sys %", "RSS MB", "peak MB");
  for (const auto& p : phases)
    std::cout << fmt::format("  {:<40} {:>9.3f} {:>11} {:>9} {:>8.2f} {:>6.0f} {:>10} {:>10}\n", p.name, p.seconds, rate(p.rows, p.seconds),
                             p.megabytes > 0 ? fmt::format("{:.1f}", p.megabytes / p.seconds) : "", p.seconds > 0 ? p.cpu_seconds / p.seconds : 0.0,
                             p.cpu_seconds > 0 ? 100 * p.system_seconds / p.cpu_seconds : 0.0,
                             std::isnan(p.resident_mb) ? "" : fmt::format("{:.1f}", p.resident_mb),
                             std::isnan(p.peak_mb) ? "" : fmt::format("{:.1f}", p.peak_mb));
}

void print_verdict(const std::string& what, double seconds, double peak_mb) {
  std::cout << fmt::format("  {:<44} {:7.3f} s  (target < {:g} s): {}   peak {:8.1f} MB  (target < {:g} MB): {}\n", what, seconds,
                           kTargetSeconds, seconds < kTargetSeconds ? "PASS" : "FAIL", peak_mb, kTargetPeakMB,
                           peak_mb < kTargetPeakMB ? "PASS" : "FAIL");
}

// ---- the in-process phases ----------------------------------------------------------------------

// The whole of one path (in-process, or the command line), for the verdict.
struct PathTotals {
  double seconds = 0;
  double peak_mb = 0;
  bool complete = false;
};

// The model's settings read as `sidc fit` reads them (runtime/solve/options_from_settings.hpp).
sidc::EvaluationOptions evaluation_options(const sidc::ir::Model& model) {
  return sidc::evaluation_options(sidc::evaluation_settings(model.settings));
}

void print_estimates(const sidc::LeastSquaresSummary& s) {
  const Oscillator truth;
  const std::vector<std::pair<std::string, double>> expected{{"m", truth.m},       {"c[1]", truth.c1}, {"c[3]", truth.c3},
                                                             {"s[1]", truth.s1}, {"s[3]", truth.s3}, {"d[2]", truth.d2}};
  std::string line;
  double largest_other = 0;  // the 14 candidates that are not in the system should come out ~0
  for (const auto& p : s.parameters) {
    bool in_system = false;
    for (const auto& [name, value] : expected)
      if (p.name == name) {
        line += fmt::format(" {}={:.7g}", name, p.value);
        in_system = true;
      }
    if (!in_system) largest_other = std::max(largest_other, std::abs(p.value));
  }
  line += fmt::format("; largest other |estimate| {:.2g}", largest_other);
  std::cout << fmt::format("    -> {}, rank {}, R^2 {:.9f}, condition {:.3g} after scaling; {}\n", to_string(s.termination), s.rank,
                           s.r_squared, s.condition_after, s.arithmetic);
  std::cout << "      " << line << "\n";
  static bool truth_shown = false;
  if (!std::exchange(truth_shown, true)) std::cout << "       (true: m=1 c[1]=0.3 c[3]=0.05 s[1]=1 s[3]=0.5 d[2]=0.2, the other 14 are 0)\n";
}

PathTotals run_library(const fs::path& model_path, const fs::path& csv_path, std::size_t rows, const BenchOptions& bench) {
  using namespace sidc;
  PathTotals totals;
  std::cout << "\nin-process phases (sidc libraries):\n";

  std::optional<ir::Model> model;
  auto compile_model = [&] {
    std::ifstream in(model_path);
    std::stringstream text;
    text << in.rdbuf();
    CompileResult r = compile(std::make_shared<const SourceFile>(model_path.string(), text.str()), CompileOptions{});
    if (!r.ok() || !r.integrated) {
      std::cerr << r.diagnostics.render_all();
      return false;
    }
    model = std::move(*r.integrated);
    return true;
  };
  if (!measure("compile (model text -> operations)", 0, compile_model)) return totals;

  std::optional<Record> record;
  const double csv_mb = static_cast<double>(fs::file_size(csv_path)) / 1e6;
  auto parse = [&] {
    auto r = read_csv(csv_path.string());
    if (auto* d = std::get_if<Diagnostic>(&r)) {
      std::cerr << render(*d) << "\n";
      return false;
    }
    record = std::get<Record>(std::move(r));
    return true;
  };
  if (!measure("parse (read_csv)", static_cast<double>(rows), parse, csv_mb)) return totals;

  std::vector<SampledRecord> sampled;  // what fit() takes: one record
  auto bind = [&] {
    auto r = bind_record(*record, model->data.front(), *model, BindOptions{});
    if (auto* d = std::get_if<Diagnostic>(&r)) {
      std::cerr << render(*d) << "\n";
      return false;
    }
    sampled.push_back(std::get<SampledRecord>(std::move(r)));
    return true;
  };
  if (!measure("bind (bind_record)", static_cast<double>(rows), bind)) return totals;
  // `sidc fit` keeps the Record alive until the fit is done (it is a temporary of its loop); the
  // bench frees it here, which flatters the later RSS figures slightly, not the peak.
  record.reset();

  // The fit exactly as `sidc fit` runs it: runtime/solve/fit.cpp's fit() with the model's settings. At
  // these sizes it streams: row blocks evaluated and folded into the triangular factor on every
  // core; its own clocks split the time into evaluation, folding and the final p x p solve.
  const EvaluationOptions evaluation = evaluation_options(*model);
  FitOptions fit_options;
  fit_options.evaluation = evaluation;
  if (bench.block_rows > 0) fit_options.stream_block_rows = bench.block_rows;
  if (bench.threads > 0) fit_options.stream_threads = bench.threads;
  std::optional<FitSummary> summary;
  auto run_fit = [&] {
    auto r = fit(*model, sampled, fit_options);
    if (auto* d = std::get_if<Diagnostic>(&r)) {
      std::cerr << render(*d) << "\n";
      return false;
    }
    summary = std::get<FitSummary>(std::move(r));
    return true;
  };
  if (!measure("fit (evaluate + fold + solve)", static_cast<double>(rows), run_fit)) return totals;
  const GroupFit& g = summary->groups.front();
  const double n = static_cast<double>(g.summary.n);
  std::cout << fmt::format("    -> {}\n", g.streamed.empty() ? "solved dense (whole design in memory)" : "solved: " + g.streamed);
  std::cout << fmt::format("    -> inside fit: evaluate {:.3f} thread-s ({} rows/s per thread), fold {:.3f} thread-s ({} rows/s per thread), "
                           "solve {:.4f} s\n",
                           g.evaluate_seconds, rate(n, g.evaluate_seconds), g.fold_seconds, rate(n, g.fold_seconds), g.solve_seconds);
  // Not measured phases, but the split of the one above, for the table (not counted in the total).
  const double fit_seconds = phases.back().seconds;
  const double thread_seconds = g.evaluate_seconds + g.fold_seconds;
  if (thread_seconds > 0) {
    const double share = (fit_seconds - g.solve_seconds) / thread_seconds;  // wall seconds per thread-second
    phases.push_back(Phase{"  of which evaluate (wall share)", g.evaluate_seconds * share, n, 0, g.evaluate_seconds, 0, NAN, NAN, false});
    phases.push_back(Phase{"  of which fold into R (wall share)", g.fold_seconds * share, n, 0, g.fold_seconds, 0, NAN, NAN, false});
    phases.push_back(Phase{"  of which solve (p x p)", g.solve_seconds, 0, 0, g.solve_seconds, 0, NAN, NAN, false});
  }
  print_estimates(g.summary);
  for (const auto& p : phases)
    if (p.counts_to_total) totals.seconds += p.seconds;
  totals.peak_mb = peak_mb_self();
  totals.complete = true;
  return totals;
}

// ---- the command-line path ----------------------------------------------------------------------

struct ChildRun {
  int exit_status = -1;
  double seconds = 0, cpu_seconds = 0, system_seconds = 0, peak_mb = 0;
};

// Runs argv in `dir` with stdout and stderr to files; waits with wait4 for the child's rusage.
std::optional<ChildRun> run_child(const std::vector<std::string>& args, const fs::path& dir, const fs::path& out,
                                  const fs::path& err) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const auto t0 = Clock::now();
  const pid_t pid = fork();
  if (pid < 0) return std::nullopt;
  if (pid == 0) {
    const int o = open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int e = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (o < 0 || e < 0 || dup2(o, 1) < 0 || dup2(e, 2) < 0 || chdir(dir.c_str()) != 0) _exit(127);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  rusage u{};
  if (wait4(pid, &status, 0, &u) != pid) return std::nullopt;
  ChildRun r;
  r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  r.exit_status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.cpu_seconds = seconds_of(u.ru_utime) + seconds_of(u.ru_stime);
  r.system_seconds = seconds_of(u.ru_stime);
  r.peak_mb = static_cast<double>(u.ru_maxrss) * 1024.0 / 1e6;
  return r;
}

PathTotals run_command_line(const fs::path& dir, const std::string& model_name, std::size_t rows, double csv_mb) {
  PathTotals totals;
  const std::string sidc = SIDC_BINARY;
  std::cout << fmt::format("\ncommand line ({}):\n", sidc);
  auto child = [&](const std::string& name, std::vector<std::string> args, const std::string& log, double count, double mb) {
    std::cout << fmt::format("  {:<40}", name) << std::flush;
    auto r = run_child(args, dir, dir / (log + ".out"), dir / (log + ".err"));
    if (!r) {
      std::cout << "could not start\n";
      return false;
    }
    std::cout << fmt::format("{:8.3f} s   peak {:8.1f} MB   exit {}\n", r->seconds, r->peak_mb, r->exit_status);
    phases.push_back(Phase{name, r->seconds, count, mb, r->cpu_seconds, r->system_seconds, NAN, r->peak_mb, true});
    totals.seconds += r->seconds;
    totals.peak_mb = std::max(totals.peak_mb, r->peak_mb);
    if (r->exit_status != 0) std::cout << fmt::format("    -> see {}\n", (dir / (log + ".err")).string());
    return r->exit_status == 0;
  };
  const std::string compiled = "fit_bench.sidc.json";
  if (!child("sidc compile", {sidc, "compile", model_name, "-o", compiled}, "compile", 0, 0)) return totals;
  // --no-validate: the target is the fit, CSV to report; the validation that `sidc fit` runs after
  // it (thesis section 2-4: RK4 through the whole record, 10 steps per sample) is a separate cost
  // (bench/README.md gives it).
  if (!child("sidc fit --no-validate", {sidc, "fit", compiled, "--no-validate"}, "fit", static_cast<double>(rows), csv_mb)) return totals;
  std::cout << fmt::format("    -> report in {}\n", (dir / "fit.out").string());
  totals.complete = true;
  return totals;
}

}  // namespace

int main(int argc, char** argv) {
  const auto options = parse_arguments(argc, argv);
  if (!options) return 2;
  const fs::path dir = options->dir;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) {
    std::cerr << fmt::format("fit_bench: cannot create {}: {}\n", dir.string(), ec.message());
    return 1;
  }
  const std::string csv_name = fmt::format("fit-{}.csv", options->rows);
  const fs::path csv_path = dir / csv_name;
  const std::string model_name = "fit_bench.sid";
  const fs::path model_path = dir / model_name;

  std::cout << fmt::format("fit_bench: {} rows, 20 candidate operations, {} hardware threads, directory {}\n", options->rows,
                           std::thread::hardware_concurrency(), dir.string());
  std::cout << "  load average at start: " << load_average() << "\n";
  {
    std::ofstream model(model_path);
    model << model_text(csv_name);
  }
  if (options->keep && fs::exists(csv_path)) {
    std::cout << fmt::format("  reusing {} ({:.1f} MB)\n", csv_path.string(), static_cast<double>(fs::file_size(csv_path)) / 1e6);
  } else {
    std::cout << fmt::format("  generating {} (RK4, step {:g} s) ... ", csv_path.string(), kStep) << std::flush;
    const auto t0 = Clock::now();
    std::string error;
    if (!write_record(csv_path, options->rows, error)) {
      std::cerr << "\nfit_bench: " << error << "\n";
      return 1;
    }
    std::cout << fmt::format("{:.1f} MB in {:.2f} s (not part of the fit)\n", static_cast<double>(fs::file_size(csv_path)) / 1e6,
                             std::chrono::duration<double>(Clock::now() - t0).count());
  }
  const double csv_mb = static_cast<double>(fs::file_size(csv_path)) / 1e6;

  PathTotals library, command_line;
  // The children run first, while this process is small: a forked child's peak (from wait4)
  // starts at the resident size it inherits at the fork (Linux counts the copied mapping until
  // exec), so it is measured before the in-process phases grow this process.
  if (options->command_line) {
    std::cout << fmt::format("\n(this process's resident size at the fork: {:.1f} MB, an upper bound on what the children's peak"
                             " can inherit)", resident_mb_self());
    command_line = run_command_line(dir, model_name, options->rows, csv_mb);
    print_table("command line (child processes; peak MB from wait4)");
    phases.clear();
  }
  if (options->library) {
    library = run_library(model_path, csv_path, options->rows, *options);
    print_table("in-process phases");
    std::cout << "  (total = compile + parse + bind + fit; the `of which` rows split the fit by its own clocks, cpu/wall there is\n"
                 "   thread-seconds over the wall share; peak MB is this process's high-water mark so far)\n";
  }

  std::cout << "\nload average at end: " << load_average() << "\n";
  std::cout << fmt::format("verdict ({} rows; targets: whole fit < {:g} s, peak < {:g} MB):\n", options->rows, kTargetSeconds, kTargetPeakMB);
  if (library.complete) print_verdict("in-process, CSV to parameters", library.seconds, library.peak_mb);
  else if (options->library) std::cout << "  in-process phases did not complete\n";
  if (command_line.complete) print_verdict("sidc compile && sidc fit, CSV to report", command_line.seconds, command_line.peak_mb);
  else if (options->command_line) std::cout << "  command line did not complete\n";

  if (!options->keep) fs::remove(csv_path, ec);
  const bool pass = (!options->library || (library.complete && library.seconds < kTargetSeconds && library.peak_mb < kTargetPeakMB)) &&
                    (!options->command_line ||
                     (command_line.complete && command_line.seconds < kTargetSeconds && command_line.peak_mb < kTargetPeakMB));
  return pass ? 0 : 3;
}
