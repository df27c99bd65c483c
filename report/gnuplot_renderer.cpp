// Figure -> gnuplot script -> SVG and PNG; see gnuplot_renderer.hpp for the guarantees.
#include "report/gnuplot_renderer.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include "report/atomic_file.hpp"

extern char** environ;

namespace sidc {
namespace {

bool valid_stem(const std::string& name) {
  if (name.empty() || name.front() == '.' || name.size() > 200) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
           c == '.';
  });
}

std::string check_figure(const Figure& figure) {
  if (!valid_stem(figure.name))
    return fmt::format("figure name `{}` is not a plain file stem (letters, digits, '_', '-', '.' not first)",
                       figure.name);
  if (figure.curves.empty()) return fmt::format("figure `{}` has no curve", figure.name);
  for (const auto& curve : figure.curves) {
    if (curve.x.size() != curve.y.size())
      return fmt::format("curve `{}` of figure `{}` has {} x values and {} y values", curve.label, figure.name,
                         curve.x.size(), curve.y.size());
    if (curve.x.empty()) return fmt::format("curve `{}` of figure `{}` has no points", curve.label, figure.name);
  }
  return "";
}

std::string number(double v) { return std::isfinite(v) ? fmt::format("{:.17g}", v) : std::string("NaN"); }

std::string style_clause(const Curve& curve) {
  switch (curve.style) {
    case Curve::Style::line: return "with lines lw 1.5";
    case Curve::Style::dashed_line: return "with lines lw 1.5 dt 2";
    // A few marks (a start point) are drawn large enough to see; many (a record) small.
    case Curve::Style::points: return curve.x.size() < 20 ? "with points pt 7 ps 1.2" : "with points pt 7 ps 0.45";
    case Curve::Style::impulses: return "with impulses lw 2";
  }
  return "with lines";
}

// Reads what the child writes on `fd` until EOF or the deadline; then reaps it (killing it at the
// deadline). Returns the exit status as waitpid gives it, or -1 on time-out.
int collect(pid_t pid, int fd, std::chrono::steady_clock::time_point deadline, std::string* output) {
  bool open = true;
  char buffer[4096];
  while (open) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(std::min<long long>(left.count(), 1000)));
    if (ready < 0 && errno != EINTR) break;
    if (ready <= 0) continue;
    const ssize_t got = ::read(fd, buffer, sizeof buffer);
    if (got > 0) {
      if (output->size() < (1u << 20)) output->append(buffer, static_cast<std::size_t>(got));
    } else if (got == 0 || errno != EINTR) {
      open = false;
    }
  }
  int status = 0;
  while (true) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) return status;
    if (done < 0 && errno != EINTR) return status;
    if (std::chrono::steady_clock::now() >= deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      return -1;
    }
    ::usleep(2000);
  }
}

}  // namespace

bool RenderOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string text) {
    if (why) *why = std::move(text);
    return false;
  };
  if (width < 100 || width > 10000 || height < 100 || height > 10000)
    return fail(fmt::format("picture size {}x{} is outside 100..10000 pixels", width, height));
  if (!svg && !png) return fail("neither SVG nor PNG was asked for");
  if (!(timeout_seconds > 0)) return fail("timeout_seconds must be positive");
  if (decimate_above < 16) return fail("decimate_above must be at least 16");
  return true;
}

const char* to_string(RenderSummary::Status status) {
  switch (status) {
    case RenderSummary::Status::success: return "success";
    case RenderSummary::Status::invalid_options: return "invalid options";
    case RenderSummary::Status::invalid_figure: return "invalid figure";
    case RenderSummary::Status::gnuplot_missing: return "gnuplot missing";
    case RenderSummary::Status::gnuplot_failed: return "gnuplot failed";
    case RenderSummary::Status::timed_out: return "timed out";
    case RenderSummary::Status::io_error: return "input/output error";
  }
  return "unknown";
}

std::string gnuplot_quote(const std::string& text) {
  // Double quotes: gnuplot 5.4 mis-reads a run of doubled quotes in a single-quoted string
  // (y'' written as 'y''''' is a syntax error).
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n' || c == '\r' || c == '\t') {
      out += ' ';
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::vector<std::size_t> decimate_for_drawing(const std::vector<double>& x, const std::vector<double>& y,
                                              std::size_t runs) {
  const std::size_t n = std::min(x.size(), y.size());
  std::vector<std::size_t> kept;
  if (runs == 0 || n <= 4 * runs) {
    kept.resize(n);
    for (std::size_t i = 0; i < n; ++i) kept[i] = i;
    return kept;
  }
  kept.reserve(4 * runs + 2);
  for (std::size_t r = 0; r < runs; ++r) {
    const std::size_t begin = n * r / runs, end = n * (r + 1) / runs;
    std::size_t extreme[4] = {n, n, n, n};  // argmin x, argmax x, argmin y, argmax y
    for (std::size_t i = begin; i < end; ++i) {
      if (!std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
      if (extreme[0] == n || x[i] < x[extreme[0]]) extreme[0] = i;
      if (extreme[1] == n || x[i] > x[extreme[1]]) extreme[1] = i;
      if (extreme[2] == n || y[i] < y[extreme[2]]) extreme[2] = i;
      if (extreme[3] == n || y[i] > y[extreme[3]]) extreme[3] = i;
    }
    std::sort(std::begin(extreme), std::end(extreme));
    for (std::size_t k = 0; k < 4; ++k)
      if (extreme[k] != n && (kept.empty() || kept.back() != extreme[k])) kept.push_back(extreme[k]);
  }
  return kept;
}

std::string gnuplot_script(const Figure& figure, const RenderOptions& options, const std::string& svg_path,
                           const std::string& png_path) {
  std::string script;
  script += "# written by sidc (report/gnuplot_renderer.cpp)\nreset\n";
  // Data first, as named blocks, so both terminals draw the same numbers from one script.
  const std::size_t runs = static_cast<std::size_t>(options.width);
  for (std::size_t c = 0; c < figure.curves.size(); ++c) {
    const auto& curve = figure.curves[c];
    script += fmt::format("$c{} << EOD\n", c);
    if (curve.x.size() > options.decimate_above) {
      for (std::size_t i : decimate_for_drawing(curve.x, curve.y, runs))
        script += number(curve.x[i]) + ' ' + number(curve.y[i]) + '\n';
    } else {
      for (std::size_t i = 0; i < curve.x.size(); ++i) script += number(curve.x[i]) + ' ' + number(curve.y[i]) + '\n';
    }
    script += "EOD\n";
  }
  script += "set encoding utf8\n";
  script += "set title " + gnuplot_quote(figure.title) + "\n";
  script += "set xlabel " + gnuplot_quote(figure.x_label) + "\n";
  script += "set ylabel " + gnuplot_quote(figure.y_label) + "\n";
  script += "set grid lc rgb '#d0d0d0'\nset border lw 1\n";
  // The key goes under the plot, one entry per row; the bottom margin is set to hold it, because
  // gnuplot's own estimate lets a long x label overlap the key.
  std::size_t entries = figure.band ? 1 : 0;
  bool right_axis = false;
  for (const auto& curve : figure.curves) {
    entries += curve.label.empty() ? 0 : 1;
    right_axis = right_axis || curve.right_axis;
  }
  if (entries == 0) script += "unset key\n";
  else script += fmt::format("set key below vertical\nset bmargin {}\n", 4 + entries);
  if (right_axis) {
    script += "set ytics nomirror\nset y2tics\n";
    script += "set y2label " + gnuplot_quote(figure.y2_label) + "\n";
  }
  // Room above the curves for the notes, so they do not hide the data.
  // Stems at integer lags keep half a lag of room at both ends, so the first and last stems are not
  // drawn on the frame.
  const bool stems = std::any_of(figure.curves.begin(), figure.curves.end(),
                                 [](const Curve& curve) { return curve.style == Curve::Style::impulses; });
  if (stems) script += "set autoscale xfix\n";
  if (stems || !figure.notes.empty())
    script += fmt::format("set offsets {}, {}, graph {:.2f}, 0\n", stems ? "0.5" : "0", stems ? "0.5" : "0",
                          0.1 * static_cast<double>(figure.notes.size()));
  // `set offsets` does not reach the right-hand axis: give it the same room by an explicit range.
  if (right_axis && !figure.notes.empty()) {
    double low = INFINITY, high = -INFINITY;
    for (const auto& curve : figure.curves)
      if (curve.right_axis)
        for (double v : curve.y)
          if (std::isfinite(v)) low = std::min(low, v), high = std::max(high, v);
    if (low < high) {
      const double span = high - low;
      script += fmt::format("set y2range [{}:{}]\n", number(low - 0.05 * span),
                            number(high + span * (0.05 + 0.1 * static_cast<double>(figure.notes.size()))));
    }
  }
  script += "set style textbox opaque noborder\n";
  if (figure.zero_axis) script += "set xzeroaxis lt -1 lw 1\n";
  for (std::size_t i = 0; i < figure.notes.size(); ++i)
    script += fmt::format("set label {} {} at graph 0.02, graph {:.3f} left front boxed\n", i + 1,
                          gnuplot_quote(figure.notes[i]), 0.95 - 0.06 * static_cast<double>(i));
  for (std::size_t i = 0; i < figure.vertical_lines.size(); ++i) {
    const auto& line = figure.vertical_lines[i];
    script += fmt::format("set arrow {} from first {}, graph 0 to first {}, graph 1 nohead dt 3 lc rgb '#606060'\n",
                          i + 1, number(line.x), number(line.x));
    if (!line.label.empty())
      script += fmt::format("set label {} {} at first {}, graph 1.02 center\n", 100 + i, gnuplot_quote(line.label),
                            number(line.x));
  }
  std::vector<std::string> plots;
  if (figure.band) {
    script += fmt::format(
        "set object 1 rect from graph 0, first {} to graph 1, first {} behind fc rgb '#dce6f4' fs solid 0.6 noborder\n",
        number(figure.band->low), number(figure.band->high));
    plots.push_back(fmt::format("{} with lines dt 2 lw 1 lc rgb '#3060a0' title {}", number(figure.band->high),
                                gnuplot_quote(figure.band->label)));
    plots.push_back(fmt::format("{} with lines dt 2 lw 1 lc rgb '#3060a0' notitle", number(figure.band->low)));
  }
  for (std::size_t c = 0; c < figure.curves.size(); ++c) {
    const auto& curve = figure.curves[c];
    plots.insert(plots.begin() + static_cast<long>(c),
                 fmt::format("$c{} using 1:2 {}{} lc {} {}", c, curve.right_axis ? "axes x1y2 " : "", style_clause(curve),
                             curve.colour_of >= 0 ? curve.colour_of + 1 : static_cast<int>(c) + 1,
                             curve.label.empty() ? std::string("notitle") : "title " + gnuplot_quote(curve.label)));
  }
  std::string plot = "plot ";
  for (std::size_t i = 0; i < plots.size(); ++i) plot += (i ? ", \\\n     " : "") + plots[i];
  plot += "\n";

  bool first = true;
  auto output = [&](const std::string& terminal, const std::string& path) {
    if (path.empty()) return;
    script += fmt::format("set terminal {} size {},{} noenhanced font {} background rgb 'white'\n", terminal,
                          options.width, options.height, gnuplot_quote(options.font));
    script += "set output " + gnuplot_quote(path) + "\n";
    script += first ? plot : "replot\n";
    script += "unset output\n";
    first = false;
  };
  output("svg", svg_path);
  output("pngcairo", png_path);
  return script;
}

RenderSummary render_figure(const Figure& figure, const std::string& directory, const RenderOptions& options) {
  using Status = RenderSummary::Status;
  RenderSummary summary;
  std::string why;
  if (!options.is_valid(&why)) {
    summary.status = Status::invalid_options;
    summary.message = why;
    return summary;
  }
  if (const auto problem = check_figure(figure); !problem.empty()) {
    summary.status = Status::invalid_figure;
    summary.message = problem;
    return summary;
  }
  if (::access(options.gnuplot.c_str(), X_OK) != 0) {
    summary.status = Status::gnuplot_missing;
    summary.message = fmt::format(
        "gnuplot was not found at {} (needed for pictures): install it with `apt-get install gnuplot-nox` "
        "(scripts/setup.sh does)",
        options.gnuplot);
    return summary;
  }
  std::error_code error;
  std::filesystem::create_directories(directory.empty() ? "." : directory, error);
  if (error) {
    summary.status = Status::io_error;
    summary.message = fmt::format("cannot create the picture directory {}: {}", directory, error.message());
    return summary;
  }
  const std::filesystem::path base = std::filesystem::path(directory.empty() ? "." : directory) / figure.name;
  const std::string svg_final = base.string() + ".svg", png_final = base.string() + ".png";

  // Temporary outputs and the script, all in the output directory, locked while gnuplot draws;
  // each TemporaryFile removes its file on every path out that does not rename it into place.
  TemporaryFile svg_file = options.svg ? create_temporary_beside(svg_final, &why) : TemporaryFile();
  TemporaryFile png_file = options.png && !(options.svg && svg_file.empty()) ? create_temporary_beside(png_final, &why) : TemporaryFile();
  TemporaryFile script_file = !(options.svg && svg_file.empty()) && !(options.png && png_file.empty()) ? create_temporary_beside(base.string() + ".gp", &why)
                                                                                                       : TemporaryFile();
  auto cleanup = [&]() {
    svg_file.remove();
    png_file.remove();
    script_file.remove();
  };
  const std::string svg_temporary = svg_file.path(), png_temporary = png_file.path(), script_path = script_file.path();
  if ((options.svg && svg_temporary.empty()) || (options.png && png_temporary.empty()) || script_path.empty()) {
    cleanup();
    summary.status = Status::io_error;
    summary.message = why;
    return summary;
  }
  const std::string script = gnuplot_script(figure, options, svg_temporary, png_temporary);
  for (const auto& curve : figure.curves) {
    const bool decimated = curve.x.size() > options.decimate_above;
    summary.decimated = summary.decimated || decimated;
    summary.points_drawn +=
        decimated ? decimate_for_drawing(curve.x, curve.y, static_cast<std::size_t>(options.width)).size()
                  : curve.x.size();
  }
  if (!write_temporary(script_file, script, &why)) {
    cleanup();
    summary.status = Status::io_error;
    summary.message = why;
    return summary;
  }

  // gnuplot < script 2> pipe > /dev/null, without a shell.
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0) {
    cleanup();
    summary.status = Status::io_error;
    summary.message = std::string("cannot create a pipe for gnuplot: ") + std::strerror(errno);
    return summary;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, script_path.c_str(), O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], 2);
  std::string program = options.gnuplot;
  char* argv[] = {program.data(), nullptr};
  const auto start = std::chrono::steady_clock::now();
  pid_t pid = 0;
  // sidc ignores SIGPIPE (cli/main.cpp: a closed stdout is reported, not a death); gnuplot gets the
  // default back, as any program started from a shell has it.
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t default_signals;
  sigemptyset(&default_signals);
  sigaddset(&default_signals, SIGPIPE);
  posix_spawnattr_setsigdefault(&attributes, &default_signals);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF);
  const int spawned = ::posix_spawn(&pid, program.c_str(), &actions, &attributes, argv, environ);
  posix_spawnattr_destroy(&attributes);
  posix_spawn_file_actions_destroy(&actions);
  ::close(pipe_fds[1]);
  if (spawned != 0) {
    ::close(pipe_fds[0]);
    cleanup();
    summary.status = spawned == ENOENT || spawned == EACCES ? Status::gnuplot_missing : Status::gnuplot_failed;
    summary.message = fmt::format("cannot start {}: {}; install gnuplot with `apt-get install gnuplot-nox`",
                                  options.gnuplot, std::strerror(spawned));
    return summary;
  }
  const auto deadline =
      start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(options.timeout_seconds));
  const int status = collect(pid, pipe_fds[0], deadline, &summary.gnuplot_stderr);
  ::close(pipe_fds[0]);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::string stderr_text = summary.gnuplot_stderr;
  while (!stderr_text.empty() && (stderr_text.back() == '\n' || stderr_text.back() == ' ')) stderr_text.pop_back();
  if (status == -1) {
    cleanup();
    summary.status = Status::timed_out;
    summary.message = fmt::format("gnuplot did not finish figure `{}` within {} s and was stopped", figure.name,
                                  options.timeout_seconds);
    return summary;
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    cleanup();
    summary.status = Status::gnuplot_failed;
    summary.message = fmt::format("gnuplot failed on figure `{}` ({}){}", figure.name,
                                  WIFEXITED(status) ? fmt::format("exit status {}", WEXITSTATUS(status))
                                                    : fmt::format("signal {}", WTERMSIG(status)),
                                  stderr_text.empty() ? std::string() : ":\n" + stderr_text);
    return summary;
  }
  // gnuplot may exit 0 yet leave an output empty (e.g. a terminal it could not open).
  for (const auto* path : {&svg_temporary, &png_temporary}) {
    if (path->empty()) continue;
    std::error_code size_error;
    if (std::filesystem::file_size(*path, size_error) == 0 || size_error) {
      cleanup();
      summary.status = Status::gnuplot_failed;
      summary.message = fmt::format("gnuplot wrote nothing for figure `{}`{}", figure.name,
                                    stderr_text.empty() ? std::string() : ":\n" + stderr_text);
      return summary;
    }
  }
  script_file.remove();
  if (options.svg) {
    if (!replace_file(svg_file, svg_final, &why)) {
      cleanup();
      summary.status = Status::io_error;
      summary.message = why;
      return summary;
    }
    summary.files.push_back(svg_final);
  }
  if (options.png) {
    if (!replace_file(png_file, png_final, &why)) {
      cleanup();
      // Both or neither: an SVG without its PNG is half a figure.
      for (const auto& file : summary.files) std::remove(file.c_str());
      summary.files.clear();
      summary.status = Status::io_error;
      summary.message = why;
      return summary;
    }
    summary.files.push_back(png_final);
  }
  summary.status = Status::success;
  return summary;
}

}  // namespace sidc
