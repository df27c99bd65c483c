// Draws a Figure (figure.hpp) as SVG and PNG by running gnuplot (Debian package gnuplot-nox,
// installed by scripts/setup.sh; terminals `svg` and `pngcairo`).
//
// Relies on: /usr/bin/gnuplot 5.x, POSIX posix_spawn, poll and waitpid. No shell is involved: the
// script (with the data inline as `$cN << EOD` blocks, every number printed with %.17g) is written
// to a temporary file that becomes gnuplot's standard input; gnuplot's standard error is read
// through a pipe.
//
// Guarantees:
// - Never aborts, never throws, never hangs: gnuplot is killed (SIGKILL) when it runs longer than
//   RenderOptions::timeout_seconds, and every outcome is a RenderSummary::Status with a message;
//   gnuplot's own error text is included verbatim (e.g. "all points y value undefined!").
// - Files appear whole or not at all: gnuplot writes to temporary names in the output directory,
//   which are renamed to NAME.svg / NAME.png only when gnuplot succeeded (atomic_file.hpp).
// - Text is drawn literally (gnuplot's `noenhanced` mode: `y_1` is not a subscript), and quotes
//   in titles, labels and paths are escaped, so no text can change the script.
// - Long curves are decimated for drawing only (decimate_for_drawing): a curve of more than
//   RenderOptions::decimate_above samples is cut into `width` runs of consecutive samples (one
//   per pixel column for a time series), and each run keeps the samples where x and y reach their
//   minimum and maximum, in their original order. For a time series that is the first, last,
//   lowest and highest sample of each pixel column (the M4 scheme), so the drawn line covers the
//   same pixels as the full one: every peak and trough survives, at most 4 * width points.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "report/figure.hpp"

namespace sidc {

struct RenderOptions {
  std::string gnuplot = "/usr/bin/gnuplot";
  int width = 800, height = 500;  // pixels (SVG user units and PNG pixels alike)
  bool svg = true, png = true;
  double timeout_seconds = 30;
  // Samples per curve beyond which a curve is decimated: 10^4-sample curves cost gnuplot about
  // 0.5 s per figure (SVG + PNG) drawn whole, 0.1 s decimated (measured, docs/pictures.md).
  std::size_t decimate_above = 5000;
  std::string font = "sans,11";
  bool is_valid(std::string* why) const;
};

struct RenderSummary {
  enum class Status { success, invalid_options, invalid_figure, gnuplot_missing, gnuplot_failed, timed_out, io_error };
  Status status = Status::invalid_figure;
  std::string message;        // why, when not success
  std::string gnuplot_stderr;  // gnuplot's standard error (warnings even on success)
  std::vector<std::string> files;  // written, e.g. DIR/NAME.svg, DIR/NAME.png
  std::size_t points_drawn = 0;    // after decimation, all curves
  bool decimated = false;
  double seconds = 0;  // wall time of the gnuplot run
  bool ok() const { return status == Status::success; }
};

const char* to_string(RenderSummary::Status status);

// Renders `figure` to DIRECTORY/NAME.svg and/or DIRECTORY/NAME.png (creating DIRECTORY).
RenderSummary render_figure(const Figure& figure, const std::string& directory, const RenderOptions& options);

// The gnuplot script render_figure runs (for inspection and tests); "" paths leave a format out.
std::string gnuplot_script(const Figure& figure, const RenderOptions& options, const std::string& svg_path,
                           const std::string& png_path);

// Indices of the samples kept when drawing a curve of x.size() samples in `runs` runs (see above);
// all indices when x.size() <= 4 * runs. Non-finite samples are dropped from decimated runs.
std::vector<std::size_t> decimate_for_drawing(const std::vector<double>& x, const std::vector<double>& y,
                                              std::size_t runs);

// A string as a double-quoted gnuplot string literal (backslash and " escaped; newlines become spaces).
std::string gnuplot_quote(const std::string& text);

}  // namespace sidc
