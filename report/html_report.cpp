// The self-contained HTML report; see html_report.hpp.
#include "report/html_report.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "report/atomic_file.hpp"

namespace sidc {
namespace {

std::string number(double v, int digits) {
  if (std::isnan(v)) return "&mdash;";
  if (std::isinf(v)) return v > 0 ? "&infin;" : "&minus;&infin;";
  return fmt::format("{:.{}g}", v, digits);
}

// Kept short: the report must print on one or two A4 pages.
constexpr const char* style_sheet = R"css(
body { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; font-size: 10pt; color: #111;
       max-width: 190mm; margin: 1em auto; line-height: 1.35; }
h1 { font-size: 15pt; margin: 0 0 0.2em 0; }
h2 { font-size: 12pt; margin: 1em 0 0.3em 0; border-bottom: 1px solid #999; }
h3 { font-size: 10.5pt; margin: 0.8em 0 0.2em 0; }
p.meta { color: #444; margin: 0 0 0.6em 0; }
pre { font-size: 8.5pt; background: #f4f4f4; padding: 0.4em 0.6em; white-space: pre-wrap; margin: 0.3em 0; }
table { border-collapse: collapse; font-size: 9pt; margin: 0.3em 0; }
th, td { border: 1px solid #bbb; padding: 0.15em 0.5em; text-align: right; }
th { background: #eee; }
td.name, th.name { text-align: left; font-family: "DejaVu Sans Mono", monospace; }
.verdict { font-style: italic; }
.figures { display: flex; flex-wrap: wrap; gap: 0.5em; }
figure { margin: 0; flex: 1 1 100%; break-inside: avoid; page-break-inside: avoid; }
figure svg { width: 100%; height: auto; display: block; }
figcaption { font-size: 8.5pt; color: #333; }
figcaption a { margin-left: 0.5em; }
figure:target { position: fixed; inset: 0; z-index: 10; background: #fff; padding: 1em; overflow: auto; }
figure:target svg { max-height: 90vh; }
figure .close { display: none; }
figure:target .close { display: inline; }
figure:target .enlarge { display: none; }
@page { size: A4; margin: 15mm; }
@media print { body { margin: 0; max-width: none; } h2 { break-after: avoid; } figcaption a { display: none; } }
)css";

void figures_html(const std::vector<ReportFigure>& figures, std::size_t* counter, std::string& out) {
  if (figures.empty()) return;
  out += "<div class=\"figures\">\n";
  for (const auto& figure : figures) {
    const std::string svg = inline_svg(figure.svg, fmt::format("f{}-", ++*counter));
    // Full column width, and a click shows it over the whole window (CSS :target; no script, so
    // the page stays self-contained).
    const std::string id = fmt::format("figure-{}", *counter);
    out += "<figure id=\"" + id + "\">\n";
    out += svg.empty() ? "<p>(picture not available)</p>\n" : "<a href=\"#" + id + "\">" + svg + "</a>\n";
    out += "<figcaption>" + html_escape(figure.caption) + "<a class=\"enlarge\" href=\"#" + id + "\">enlarge</a><a class=\"close\" href=\"#\">close</a>" +
           "</figcaption>\n</figure>\n";
  }
  out += "</div>\n";
}

}  // namespace

std::string html_escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string inline_svg(const std::string& svg, const std::string& id_prefix) {
  const auto start = svg.find("<svg");
  if (start == std::string::npos) return "";
  const auto end = svg.rfind("</svg>");
  if (end == std::string::npos || end < start) return "";
  std::string body = svg.substr(start, end + 6 - start);
  // Namespace declarations are names, not references, but a self-contained page should not even
  // mention an address; HTML5's parser puts inline <svg> in the SVG namespace without them.
  for (const char* declaration : {"xmlns=\"http://www.w3.org/2000/svg\"", "xmlns:xlink=\"http://www.w3.org/1999/xlink\"",
                                  "xmlns='http://www.w3.org/2000/svg'", "xmlns:xlink='http://www.w3.org/1999/xlink'"}) {
    for (auto at = body.find(declaration); at != std::string::npos; at = body.find(declaration))
      body.erase(at, std::string(declaration).size());
  }
  if (body.find("<script") != std::string::npos) return "";
  // Only references inside the picture itself (href='#id') are allowed.
  for (std::size_t at = body.find("href="); at != std::string::npos; at = body.find("href=", at + 5)) {
    const std::size_t value = at + 5;
    if (value + 1 >= body.size() || body[value + 1] != '#') return "";
  }
  if (body.find("http") != std::string::npos) return "";
  // Every gnuplot picture defines the same ids (gpPt0, textbox, ...); one page must not repeat an id.
  if (!id_prefix.empty()) {
    for (const std::string anchor : {"id='", "id=\"", "href='#", "href=\"#", "url(#"}) {
      for (auto at = body.find(anchor); at != std::string::npos; at = body.find(anchor, at + anchor.size() + id_prefix.size()))
        body.insert(at + anchor.size(), id_prefix);
    }
  }
  return body;
}

void fill_group_from(const LeastSquaresSummary& summary, double confidence_level, ReportGroup* group) {
  group->confidence_level = confidence_level;
  group->parameters.clear();
  for (const auto& p : summary.parameters)
    group->parameters.push_back({p.name, p.value, p.standard_error, p.ci_low, p.ci_high});
  auto& s = group->statistics;
  s.n = summary.n;
  s.p = summary.p;
  s.rank = summary.rank;
  s.G = summary.G;
  s.standard_error = summary.standard_error;
  s.residual_sd = summary.residual_sd;
  s.r_squared = summary.r_squared;
  s.r_squared_centred = summary.r_squared_centred;
  s.other_r_squared = summary.r_squared_centred ? summary.uncentred_r_squared : summary.centred_r_squared;
  s.condition = summary.condition_after;
  s.termination = to_string(summary.termination);
}

std::string render_html_report(const ReportContent& content) {
  std::string out;
  std::size_t figure_count = 0;
  out += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  out += "<title>" + html_escape(content.title) + "</title>\n<style>" + style_sheet + "</style>\n</head>\n<body>\n";
  out += "<h1>" + html_escape(content.title) + "</h1>\n";
  out += "<p class=\"meta\">Model <b>" + html_escape(content.model_name) + "</b>";
  if (!content.source_file.empty()) out += " from <code>" + html_escape(content.source_file) + "</code>";
  if (!content.generated_by.empty()) out += "; " + html_escape(content.generated_by);
  out += "</p>\n";

  out += "<h2 id=\"model\">Model as fitted</h2>\n<pre>" + html_escape(content.model_text) + "</pre>\n";

  out += "<h2 id=\"settings\">Fit settings</h2>\n";
  if (content.settings.empty() && content.records.empty()) out += "<p>(defaults)</p>\n";
  if (!content.settings.empty()) {
    out += "<table>\n<tr><th class=\"name\">setting</th><th class=\"name\">value</th></tr>\n";
    for (const auto& [name, value] : content.settings)
      out += "<tr><td class=\"name\">" + html_escape(name) + "</td><td class=\"name\">" + html_escape(value) +
             "</td></tr>\n";
    out += "</table>\n";
  }
  if (!content.records.empty()) {
    out += "<p>Records:";
    for (std::size_t i = 0; i < content.records.size(); ++i)
      out += std::string(i ? ", " : " ") + "<code>" + html_escape(content.records[i]) + "</code>";
    out += "</p>\n";
  }

  for (std::size_t g = 0; g < content.groups.size(); ++g) {
    const auto& group = content.groups[g];
    out += fmt::format("<h2 id=\"group-{}\">{}</h2>\n", g + 1, html_escape(group.title));
    if (!group.equations.empty()) {
      out += "<pre>";
      for (const auto& line : group.equations) out += html_escape(line) + "\n";
      out += "</pre>\n";
    }
    out += "<h3>Parameters</h3>\n<table>\n";
    out += fmt::format(
        "<tr><th class=\"name\">parameter</th><th>estimate</th><th>standard error</th><th>{:.0f}% interval</th></tr>\n",
        group.confidence_level * 100);
    for (const auto& p : group.parameters)
      out += "<tr><td class=\"name\">" + html_escape(p.name) + "</td><td>" + number(p.estimate, 8) + "</td><td>" +
             number(p.standard_error, 3) + "</td><td>" + number(p.ci_low, 6) + " &hellip; " + number(p.ci_high, 6) +
             "</td></tr>\n";
    out += "</table>\n";

    const auto& s = group.statistics;
    out += "<h3>Statistics</h3>\n<table>\n<tr><th>n</th><th>G(a)</th><th>standard error</th><th>residual SD</th>"
           "<th>R&sup2;</th><th>condition</th><th>rank</th><th class=\"name\">termination</th></tr>\n";
    out += fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}{}; {} {}</td><td>{}</td><td>{} of {}</td>"
                       "<td class=\"name\">{}</td></tr>\n</table>\n",
                       s.n, number(s.G, 6), number(s.standard_error, 4), number(s.residual_sd, 4),
                       number(s.r_squared, 6), s.r_squared_centred ? " (centred)" : " (uncentred)",
                       s.r_squared_centred ? "uncentred" : "centred", number(s.other_r_squared, 6), number(s.condition, 3),
                       s.rank, s.p, html_escape(s.termination));
    out += "<p class=\"meta\">G(a) = sum of squared residuals (eq. 2-1.7); standard error sqrt(G/n) (thesis); "
           "residual SD sqrt(G/(n &minus; rank)); condition number of the scaled design.</p>\n";

    if (!group.validation.empty()) {
      out += "<h3>Validation: the fitted equations solved against the record</h3>\n<table>\n"
             "<tr><th class=\"name\">output</th><th class=\"name\">record</th><th>max |E|</th>"
             "<th>% error (eq. 4-1.5)</th><th>fit %</th><th class=\"name\">note</th></tr>\n";
      for (const auto& v : group.validation)
        out += "<tr><td class=\"name\">" + html_escape(v.output) + "</td><td class=\"name\">" + html_escape(v.record) +
               "</td><td>" + number(v.max_abs_error, 3) + "</td><td>" + number(v.thesis_percent, 3) + "</td><td>" +
               number(v.fit_percent, 4) + "</td><td class=\"name\">" + html_escape(v.note) + "</td></tr>\n";
      out += "</table>\n<p class=\"meta\">E = recorded &minus; simulated (eq. 4-1.4); % error = max |E| / max "
             "|recorded| &times; 100 (eq. 4-1.5); fit % = 100 (1 &minus; ||y &minus; &ycirc;|| / ||y &minus; "
             "mean y||).</p>\n";
    }
    if (!group.residual_verdicts.empty()) {
      out += "<h3>Residual tests</h3>\n<ul>\n";
      for (const auto& line : group.residual_verdicts) out += "<li class=\"verdict\">" + html_escape(line) + "</li>\n";
      out += "</ul>\n";
    }
    if (!group.local_fits.empty())
      out += "<h3>Local fits (thesis chapter V)</h3>\n<pre>" + html_escape(group.local_fits) + "</pre>\n";
    figures_html(group.figures, &figure_count, out);
  }

  if (!content.figures.empty()) {
    out += "<h2 id=\"figures\">Figures</h2>\n";
    figures_html(content.figures, &figure_count, out);
  }
  if (!content.notes.empty()) {
    out += "<h2 id=\"notes\">Notes</h2>\n<ul>\n";
    for (const auto& note : content.notes) out += "<li>" + html_escape(note) + "</li>\n";
    out += "</ul>\n";
  }
  out += "</body>\n</html>\n";
  return out;
}

ReportWriteSummary write_html_report(const ReportContent& content, const std::string& path) {
  ReportWriteSummary summary;
  const std::string html = render_html_report(content);
  std::string why;
  if (!write_file_atomically(path, html, &why)) {
    summary.message = why;
    return summary;
  }
  summary.ok = true;
  summary.bytes = html.size();
  return summary;
}

ReportFigure report_figure_from_file(const std::string& svg_path, const std::string& caption, std::string* why) {
  ReportFigure figure;
  figure.caption = caption;
  std::ifstream in(svg_path, std::ios::binary);
  if (!in) {
    if (why) *why = "cannot read " + svg_path;
    return figure;
  }
  std::ostringstream text;
  text << in.rdbuf();
  figure.svg = text.str();
  return figure;
}

}  // namespace sidc
