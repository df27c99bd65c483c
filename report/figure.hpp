// A figure as plain data: what to draw, with no knowledge of how. The builders in fit_figures.hpp
// fill it from a fit's numbers; gnuplot_renderer.hpp draws it; html_report.hpp embeds the drawing.
//
// Relies on: the standard library only. Guarantees nothing about the numbers themselves (NaN
// samples are gaps in a line); the renderer checks shapes and reports a status.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace sidc {

struct Curve {
  enum class Style {
    line,         // samples joined by straight segments (a simulated output, a function)
    dashed_line,  // the same, dashed (a supplied truth under a fitted curve)
    points,       // samples as small marks (a recorded output: what was measured)
    impulses,     // a vertical stem from 0 to each sample (correlations at integer lags)
  };
  std::string label;  // shown in the key; empty = not in the key
  std::vector<double> x, y;
  Style style = Style::line;
  bool right_axis = false;  // drawn against the right-hand y axis (Figure::y2_label): two error
                            // curves of different size in one figure, as Figs. 4-1.8/4-1.9
  int colour_of = -1;       // drawn in the colour of the figure's curve of this index (the two
                            // edges of a band); -1: its own
};

// A shaded horizontal band between two levels, with its edges dashed: the 99% confidence band of
// a residual correlation (+-2.576/sqrt(N)).
struct HorizontalBand {
  double low = 0, high = 0;
  std::string label;  // e.g. "99% band +-2.576/sqrt(N)"
};

struct VerticalLine {
  double x = 0;
  std::string label;  // written at the top of the line; may be empty
};

struct Figure {
  std::string name;     // file stem: letters, digits, '_', '-', '.' (not first); no directory
  std::string title;    // in the engineer's words, with the thesis figure it corresponds to
  std::string x_label;  // with units when known: "t [s]"
  std::string y_label;
  std::string y2_label;  // right-hand axis, used when a curve has right_axis set
  std::vector<Curve> curves;
  std::optional<HorizontalBand> band;
  std::vector<VerticalLine> vertical_lines;
  std::vector<std::string> notes;  // short lines written inside the plot's top-left corner
  bool zero_axis = false;          // draw the line y = 0 (error curves, correlations)
};

}  // namespace sidc
