// The one-page report (issue 5, item 6): one self-contained HTML file with the fit's tables and its
// pictures, ready to attach to an engineering note.
//
// Relies on: plain structs the caller fills (from FitSummary, the validation and the rendered
// figures); runtime/solve/least_squares.hpp only for the convenience group_statistics_from().
//
// Guarantees:
// - Self-contained: CSS inline in a <style> element, every picture an inline <svg> element (the
//   SVG file's XML prologue, DOCTYPE and namespace declarations removed; HTML5 does not need
//   them), no script, no link, no reference to any other file or address.
// - Every piece of caller text is HTML-escaped (& < > " '), so a parameter named `a<1>` or a
//   model line with `&` prints as written; SVG text is checked to contain no <script> element.
// - Written atomically (atomic_file.hpp): the page appears whole or not at all.
// - Prints on A4 (an @page rule, 15 mm margins; figures two to a row in print, never split).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "runtime/solve/least_squares.hpp"

namespace sidc {

struct ReportParameter {
  std::string name;
  double estimate = 0, standard_error = 0, ci_low = 0, ci_high = 0;  // NaN prints as "—"
};

struct ReportStatistics {
  std::size_t n = 0, p = 0, rank = 0;
  double G = 0;               // eq. 2-1.7
  double standard_error = 0;  // sqrt(G/n), the thesis'
  double residual_sd = 0;     // sqrt(G/(n - rank))
  double r_squared = 0;
  bool r_squared_centred = false;
  double other_r_squared = 0;  // the centred one beside an uncentred r_squared, and the other way round
  double condition = 0;       // after scaling
  std::string termination;    // "success", "rank deficient", ...
};

// One output's free-run comparison (issue 5, item 3).
struct ReportValidation {
  std::string output;
  std::string record;        // which record (the fitted one, or --validate RECORD)
  double max_abs_error = 0;  // max |E[y]|, eq. 4-1.4
  double thesis_percent = 0; // eq. 4-1.5
  double fit_percent = 0;    // 100 (1 - ||y - yhat|| / ||y - mean y||)
  std::string note;          // e.g. "the simulation diverges at t = 0.41"
};

struct ReportFigure {
  std::string caption;
  std::string svg;  // the SVG file's text (gnuplot output), embedded inline
};

struct ReportGroup {
  std::string title;                    // e.g. "Equation 1" or "Equations 1, 2"
  std::vector<std::string> equations;   // as fitted, one line each
  std::vector<ReportParameter> parameters;
  double confidence_level = 0.95;       // of the parameter intervals
  ReportStatistics statistics;
  std::vector<ReportValidation> validation;
  std::vector<std::string> residual_verdicts;  // one line each (ResidualCorrelationSummary)
  std::string local_fits;                      // the local fits' table (sidc fit --local), preformatted; empty: none
  std::vector<ReportFigure> figures;
};

struct ReportContent {
  std::string title = "sidc fit report";
  std::string model_name;
  std::string source_file;
  std::string model_text;  // the model as fitted (printed by the caller)
  std::vector<std::pair<std::string, std::string>> settings;  // fit settings, name and value
  std::vector<std::string> records;  // the records used
  std::vector<ReportGroup> groups;
  std::vector<ReportFigure> figures;  // figures that belong to no single group (phase plane, ...)
  std::vector<std::string> notes;     // closing remarks
  std::string generated_by;           // e.g. "sidc 0.1.0, 2026-11-21 20:14 UTC"
};

// Parameter table and statistics of one least-squares group.
void fill_group_from(const LeastSquaresSummary& summary, double confidence_level, ReportGroup* group);

std::string render_html_report(const ReportContent& content);

struct ReportWriteSummary {
  bool ok = false;
  std::string message;  // why, when not ok
  std::size_t bytes = 0;
};
ReportWriteSummary write_html_report(const ReportContent& content, const std::string& path);

// Reads an SVG file written by the renderer into a ReportFigure; empty svg and *why on failure.
ReportFigure report_figure_from_file(const std::string& svg_path, const std::string& caption, std::string* why);

// & < > " ' as entities.
std::string html_escape(const std::string& text);

// The SVG text prepared for inline embedding (prologue, DOCTYPE, namespace declarations removed;
// every id and its references prefixed with id_prefix, so pictures on one page cannot clash);
// "" when it is not an <svg> document or contains a <script> element or an external reference.
std::string inline_svg(const std::string& svg, const std::string& id_prefix = "");

}  // namespace sidc
