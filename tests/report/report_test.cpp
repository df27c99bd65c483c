// report/: every figure kind of issue 5 renders through gnuplot to SVG and PNG, and each file is
// checked (the SVG parses as XML and draws the curve as a path of many points; the PNG has its
// signature, a non-trivial size and the dimensions asked for); a failing, missing or hung gnuplot
// gives a clear status; long curves are decimated with their peaks kept; the HTML report has
// every section, refers to nothing outside itself and escapes what it prints.
//
// Relies on: /usr/bin/gnuplot (gnuplot-nox) and Boost.PropertyTree's XML reader. Pictures are
// left in SIDC_REPORT_TEST_DIR (the build tree) for a look.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>

#include <boost/property_tree/ptree.hpp>
#include <boost/property_tree/xml_parser.hpp>
#include <gtest/gtest.h>

#include "diagnostics/time_text.hpp"

#include "report/fit_figures.hpp"
#include "report/gnuplot_renderer.hpp"
#include "report/html_report.hpp"
#include "runtime/solve/residual_correlation.hpp"

namespace sidc {
namespace {

namespace fs = std::filesystem;

fs::path output_directory(const std::string& test) {
  const fs::path dir = fs::path(SIDC_REPORT_TEST_DIR) / test;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The SVG is well-formed XML, has the asked size, and draws at least `min_points` vertices in
// one <path> (gnuplot writes a line as "M x,y L x,y ..."; impulses as one "M..V.." per stem).
void expect_svg(const fs::path& path, int width, int height, std::size_t min_points) {
  SCOPED_TRACE(path.string());
  const std::string text = read_text(path);
  ASSERT_FALSE(text.empty());
  boost::property_tree::ptree tree;
  std::istringstream in(text);
  EXPECT_NO_THROW(boost::property_tree::read_xml(in, tree)) << "not well-formed XML";
  EXPECT_NE(text.find(std::string("width=\"") + std::to_string(width) + "\""), std::string::npos);
  EXPECT_NE(text.find(std::string("height=\"") + std::to_string(height) + "\""), std::string::npos);
  std::size_t best = 0;
  // (Searched by hand: std::regex recurses per character and overflows the stack on long paths.)
  for (auto at = text.find("<path"); at != std::string::npos; at = text.find("<path", at + 1)) {
    const auto end = text.find('>', at);
    const auto d = text.find(" d='", at);
    if (end == std::string::npos || d == std::string::npos || d > end) continue;
    std::size_t vertices = 0;
    for (std::size_t i = d + 4; i < end && text[i] != '\''; ++i) vertices += (text[i] == 'L' || text[i] == 'M' || text[i] == 'V') ? 1 : 0;
    best = std::max(best, vertices);
  }
  EXPECT_GE(best, min_points) << "no <path> draws the curve";
}

void expect_png(const fs::path& path, int width, int height) {
  SCOPED_TRACE(path.string());
  const std::string bytes = read_text(path);
  ASSERT_GE(bytes.size(), 24u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(bytes.substr(12, 4), "IHDR");
  auto big_endian = [&](std::size_t at) {
    return (static_cast<unsigned char>(bytes[at]) << 24) | (static_cast<unsigned char>(bytes[at + 1]) << 16) |
           (static_cast<unsigned char>(bytes[at + 2]) << 8) | static_cast<unsigned char>(bytes[at + 3]);
  };
  EXPECT_EQ(static_cast<int>(big_endian(16)), width);
  EXPECT_EQ(static_cast<int>(big_endian(20)), height);
  EXPECT_GT(bytes.size(), 5000u) << "a plot with axes, labels and a curve is more than a few bytes";
}

// Only the final pictures are left: no temporary outputs or scripts.
void expect_only_pictures(const fs::path& dir) {
  for (const auto& entry : fs::directory_iterator(dir)) {
    const auto name = entry.path().filename().string();
    EXPECT_NE(name.front(), '.') << "temporary file left behind: " << name;
  }
}

// A damped oscillation like section 4-1's record (y, y', y'' exactly).
struct Oscillation {
  std::vector<double> t, y, dy, ddy;
  explicit Oscillation(std::size_t n, double step) {
    const double zeta = 0.3, w = 2 * std::numbers::pi * 2.0, wd = w * std::sqrt(1 - zeta * zeta);
    for (std::size_t i = 0; i < n; ++i) {
      const double s = static_cast<double>(i) * step, e = std::exp(-zeta * w * s);
      t.push_back(s);
      y.push_back(e * std::cos(wd * s));
      dy.push_back(e * (-zeta * w * std::cos(wd * s) - wd * std::sin(wd * s)));
      ddy.push_back(e * ((zeta * zeta * w * w - wd * wd) * std::cos(wd * s) + 2 * zeta * w * wd * std::sin(wd * s)));
    }
  }
};

std::vector<double> noisy(const std::vector<double>& v, double sd, unsigned seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> normal(0, sd);
  std::vector<double> out(v);
  for (auto& x : out) x += normal(generator);
  return out;
}

ResidualCorrelationSummary correlated_residuals(std::size_t n) {
  const auto u = noisy(std::vector<double>(n, 0.0), 1, 3);
  const auto w = noisy(std::vector<double>(n, 0.0), 1, 4);
  std::vector<double> e(n);
  for (std::size_t i = 0; i < n; ++i) e[i] = w[i] + (i ? 0.4 * e[i - 1] : 0) + (i >= 2 ? 0.5 * u[i - 2] : 0);
  return residual_correlation({e}, {{"x", {u}}}, {});
}

// Every figure kind of issue 5, from one synthetic record of n samples.
std::vector<Figure> every_figure_kind(std::size_t n) {
  const Oscillation o(n, 1.0 / static_cast<double>(n));
  const SignalLabel time{"t", "s"}, y{"y", "m"};
  const auto recorded = noisy(o.y, 0.01, 1);
  std::vector<Figure> figures;
  figures.push_back(recorded_vs_simulated_figure(time, y, o.t, recorded, o.y));
  figures.push_back(simulation_error_figure(time, y, o.t, recorded, o.y));
  std::vector<double> v, c_true, c_fit;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = -24.2 + 39.8 * static_cast<double>(i) / static_cast<double>(n - 1);
    v.push_back(x);
    c_true.push_back(x < 0 ? 0.5 * x * x * x / 100 : x);
    c_fit.push_back(x < 0 ? 0.49 * x * x * x / 100 + 0.1 : 0.98 * x);
  }
  figures.push_back(reconstructed_function_figure("c(y')", {"y'", "m/s"}, {"c", "N"}, v, c_fit, c_true));
  figures.push_back(reconstructed_function_error_figure("c(y')", {"y'", "m/s"}, {"c", "N"}, v, c_fit, c_true));
  auto d1 = noisy(o.dy, 0.05, 2), d2 = noisy(o.ddy, 2, 5);
  for (std::size_t i = 0; i < 3 && i < n; ++i) d1[i] = d2[i] = NAN;  // not evaluated near the start
  figures.push_back(derivative_error_figure(time, y, o.t, {{1, d1, o.dy}, {2, d2, o.ddy}}, "Delta = 0.001"));
  figures.push_back(phase_plane_figure(y, "s", o.y, o.dy));
  const auto summary = correlated_residuals(std::max<std::size_t>(n, 200));
  figures.push_back(residual_autocorrelation_figure(summary, "1"));
  figures.push_back(residual_cross_correlation_figure(summary, 0, "1"));
  return figures;
}

TEST(GnuplotRenderer, EveryFigureKindRendersToSvgAndPng) {
  const auto dir = output_directory("kinds");
  RenderOptions options;
  options.width = 720;
  options.height = 450;
  for (const auto& figure : every_figure_kind(1000)) {
    SCOPED_TRACE(figure.name);
    const auto result = render_figure(figure, dir.string(), options);
    ASSERT_TRUE(result.ok()) << to_string(result.status) << ": " << result.message;
    ASSERT_EQ(result.files.size(), 2u);
    EXPECT_FALSE(result.decimated);
    const bool correlation = figure.name.rfind("residual_", 0) == 0;
    // A line of 1000 samples is one path of ~1000 vertices; a correlation is 26 or 51 stems.
    expect_svg(dir / (figure.name + ".svg"), options.width, options.height, correlation ? 20 : 900);
    expect_png(dir / (figure.name + ".png"), options.width, options.height);
    // The title is drawn as written (gnuplot escapes it for XML itself).
    const auto svg = read_text(dir / (figure.name + ".svg"));
    const auto first_word = figure.title.substr(0, figure.title.find(' '));
    EXPECT_NE(svg.find(first_word), std::string::npos);
  }
  expect_only_pictures(dir);
}

TEST(GnuplotRenderer, TextWithQuotesAndMarkupIsDrawnLiterally) {
  const auto dir = output_directory("quotes");
  Figure figure;
  figure.name = "quotes";
  figure.title = "it's a <b>&</b> test; y_1 ^2 @ {x}";
  figure.x_label = "x '' \"quoted\" back\\slash";
  figure.y_label = "y\nwith newline";
  figure.curves.push_back({"o'clock", {0, 1, 2}, {0, 1, 4}, Curve::Style::line});
  figure.notes.push_back("note with 'quotes'");
  const auto result = render_figure(figure, dir.string(), {});
  ASSERT_TRUE(result.ok()) << result.message;
  const auto svg = read_text(dir / "quotes.svg");
  // gnuplot escapes < and & for XML (> needs no escape in XML text); quotes and backslashes arrive.
  EXPECT_NE(svg.find("it's a &lt;b>&amp;&lt;/b> test; y_1 ^2 @ {x}"), std::string::npos);
  EXPECT_NE(svg.find(R"(x '' "quoted" back\slash)"), std::string::npos);
  expect_svg(dir / "quotes.svg", 800, 500, 3);
}

TEST(GnuplotRenderer, AllNanCurveGivesGnuplotsErrorNotACrash) {
  const auto dir = output_directory("nan");
  Figure figure;
  figure.name = "all_nan";
  figure.title = "nothing to draw";
  figure.curves.push_back({"y", {0, 1, 2}, {NAN, NAN, NAN}, Curve::Style::line});
  const auto result = render_figure(figure, dir.string(), {});
  EXPECT_EQ(result.status, RenderSummary::Status::gnuplot_failed);
  EXPECT_NE(result.message.find("all_nan"), std::string::npos) << result.message;
  EXPECT_NE(result.message.find("undefined"), std::string::npos) << result.message;
  EXPECT_TRUE(result.files.empty());
  EXPECT_FALSE(fs::exists(dir / "all_nan.svg"));
  EXPECT_FALSE(fs::exists(dir / "all_nan.png"));
  expect_only_pictures(dir);
}

TEST(GnuplotRenderer, BadFiguresAndMissingGnuplotGiveAStatus) {
  const auto dir = output_directory("bad");
  Figure figure;
  figure.name = "ok";
  figure.curves.push_back({"y", {0, 1}, {0, 1, 2}, Curve::Style::line});
  auto result = render_figure(figure, dir.string(), {});
  EXPECT_EQ(result.status, RenderSummary::Status::invalid_figure);
  EXPECT_NE(result.message.find("2 x values and 3 y values"), std::string::npos) << result.message;

  figure.curves[0].x = {0, 1, 2};
  figure.name = "../escape";
  EXPECT_EQ(render_figure(figure, dir.string(), {}).status, RenderSummary::Status::invalid_figure);
  figure.name = "ok";
  figure.curves.clear();
  EXPECT_EQ(render_figure(figure, dir.string(), {}).status, RenderSummary::Status::invalid_figure);

  figure.curves.push_back({"y", {0, 1}, {0, 1}, Curve::Style::line});
  RenderOptions missing;
  missing.gnuplot = "/nonexistent/gnuplot";
  result = render_figure(figure, dir.string(), missing);
  EXPECT_EQ(result.status, RenderSummary::Status::gnuplot_missing);
  EXPECT_NE(result.message.find("gnuplot-nox"), std::string::npos) << result.message;

  RenderOptions tiny;
  tiny.width = 10;
  EXPECT_EQ(render_figure(figure, dir.string(), tiny).status, RenderSummary::Status::invalid_options);
  expect_only_pictures(dir);
}

TEST(GnuplotRenderer, AHungGnuplotIsStoppedAtTheTimeLimit) {
  const auto dir = output_directory("hung");
  // A stand-in for gnuplot that never finishes (a test fixture, not part of sidc).
  const auto fake = dir / "fake_gnuplot";
  {
    std::ofstream out(fake);
    out << "#!/bin/sh\nexec sleep 30\n";
  }
  fs::permissions(fake, fs::perms::owner_all);
  Figure figure;
  figure.name = "hung";
  figure.curves.push_back({"y", {0, 1}, {0, 1}, Curve::Style::line});
  RenderOptions options;
  options.gnuplot = fake.string();
  options.timeout_seconds = 0.3;
  const auto start = std::chrono::steady_clock::now();
  const auto result = render_figure(figure, dir.string(), options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(result.status, RenderSummary::Status::timed_out) << result.message;
  EXPECT_LT(seconds, 3.0);
  EXPECT_FALSE(fs::exists(dir / "hung.svg"));
}

TEST(Decimation, KeepsEveryPeakAndBoundsThePointCount) {
  const std::size_t n = 1000000, runs = 1600;
  std::vector<double> x(n), y(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = static_cast<double>(i) * 1e-4;
    y[i] = std::sin(x[i]);
  }
  y[123457] = 50;    // a one-sample spike
  y[876543] = -70;   // and a one-sample dip
  const auto kept = decimate_for_drawing(x, y, runs);
  EXPECT_LE(kept.size(), 4 * runs);
  EXPECT_GE(kept.size(), 2 * runs);
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
  EXPECT_NE(std::find(kept.begin(), kept.end(), 123457u), kept.end());
  EXPECT_NE(std::find(kept.begin(), kept.end(), 876543u), kept.end());
  EXPECT_EQ(kept.front(), 0u);
  EXPECT_EQ(kept.back(), n - 1);
  // Short curves are kept whole.
  EXPECT_EQ(decimate_for_drawing({1, 2, 3}, {1, 2, 3}, runs).size(), 3u);
}

TEST(GnuplotRenderer, AMillionPointCurveIsDecimatedAndRendersQuickly) {
  const auto dir = output_directory("million");
  Figure figure;
  figure.name = "million";
  figure.title = "10^6 samples";
  Curve curve{"y", std::vector<double>(1000000), std::vector<double>(1000000), Curve::Style::line};
  for (std::size_t i = 0; i < curve.x.size(); ++i) {
    curve.x[i] = static_cast<double>(i);
    curve.y[i] = std::sin(static_cast<double>(i) * 1e-4) + (i == 500000 ? 10 : 0);
  }
  figure.curves.push_back(std::move(curve));
  const auto result = render_figure(figure, dir.string(), {});
  ASSERT_TRUE(result.ok()) << result.message;
  EXPECT_TRUE(result.decimated);
  EXPECT_LE(result.points_drawn, 4u * 800);
  RecordProperty("million_point_seconds", std::to_string(result.seconds));
  std::printf("10^6-point curve: %zu points drawn, gnuplot %.3f s\n", result.points_drawn, result.seconds);
  expect_svg(dir / "million.svg", 800, 500, 1000);
}

TEST(GnuplotRenderer, SixFiguresOfTenThousandPointsTiming) {
  const auto dir = output_directory("timing");
  const auto figures = every_figure_kind(10000);
  double seconds = 0;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < 6; ++i) {
    const auto result = render_figure(figures[i], dir.string(), {});
    ASSERT_TRUE(result.ok()) << result.message;
    seconds += result.seconds;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("6 figures of 10^4 points, SVG + PNG: gnuplot %.3f s, total %.3f s\n", seconds, wall);
  RecordProperty("six_figures_seconds", std::to_string(wall));
  EXPECT_LT(wall, 60.0);
}

ReportContent sample_report(const fs::path& pictures) {
  ReportContent content;
  content.title = "Fit of <damper> & spring";
  content.model_name = "quasi_linear";
  content.source_file = "examples/thesis_4_1/model.sid";
  content.model_text = "m*y'' + c(y') + k(y) = x  # a<b & c>d";
  content.settings = {{"delta", "0.020"}, {"derivatives", "window 7, cubic"}};
  content.records = {"record.csv"};
  content.generated_by = "sidc 0.1.0";
  ReportGroup group;
  group.title = "Equation 1";
  group.equations = {"a1*y' + a2*y = -y''"};
  LeastSquaresSummary ls;
  ls.termination = LeastSquaresSummary::Termination::success;
  ls.n = 48;
  ls.p = 2;
  ls.rank = 2;
  ls.G = 0.0123;
  ls.standard_error = 0.016;
  ls.residual_sd = 0.0164;
  ls.r_squared = 0.99991;
  ls.r_squared_centred = true;
  ls.condition_after = 12.5;
  ls.parameters = {{"a<1>", 1.2345678, 0.001, 1.2325, 1.2366}, {"a2", -3.5, NAN, NAN, NAN}};
  fill_group_from(ls, 0.95, &group);
  group.validation = {{"y", "record.csv", 0.031, 1.2, 98.7, "max at t = 0.31"}};
  group.residual_verdicts = {"residuals look white & uncorrelated"};
  std::string why;
  group.figures.push_back(report_figure_from_file((pictures / "simulated_y.svg").string(), "Fig. A: y", &why));
  group.figures.push_back(report_figure_from_file((pictures / "residual_autocorrelation_1.svg").string(), "Fig. B", &why));
  content.groups.push_back(group);
  content.figures.push_back(report_figure_from_file((pictures / "phase_plane_y.svg").string(), "phase plane", &why));
  content.notes = {"x < 3 & y > 2"};
  return content;
}

TEST(HtmlReport, HasEverySectionIsSelfContainedAndEscapes) {
  const auto dir = output_directory("html");
  for (const auto& figure : every_figure_kind(500)) ASSERT_TRUE(render_figure(figure, dir.string(), {}).ok());
  const auto content = sample_report(dir);
  ASSERT_FALSE(content.groups[0].figures[0].svg.empty());
  const auto written = write_html_report(content, (dir / "report.html").string());
  ASSERT_TRUE(written.ok) << written.message;
  const auto html = read_text(dir / "report.html");
  EXPECT_EQ(html.size(), written.bytes);

  for (const char* section : {"<h2 id=\"model\">", "<h2 id=\"settings\">", "<h2 id=\"group-1\">Equation 1</h2>",
                              "<h3>Parameters</h3>", "<h3>Statistics</h3>", "<h3>Validation", "<h3>Residual tests</h3>",
                              "<h2 id=\"figures\">", "<h2 id=\"notes\">", "<style>", "@page"})
    EXPECT_NE(html.find(section), std::string::npos) << "missing: " << section;
  for (const char* statistic : {"<th>n</th>", "G(a)", "standard error", "residual SD", "R&sup2;", "condition", "rank",
                                "95% interval", "max |E|", "eq. 4-1.5", "fit %"})
    EXPECT_NE(html.find(statistic), std::string::npos) << "missing: " << statistic;
  EXPECT_NE(html.find("1.2345678"), std::string::npos);
  EXPECT_NE(html.find("&mdash;"), std::string::npos) << "a NaN standard error prints as a dash";

  // Self-contained: no address, no file reference, no script; the three pictures are inline.
  EXPECT_EQ(html.find("http"), std::string::npos);
  EXPECT_EQ(html.find("src="), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<?xml"), std::string::npos);
  std::size_t svgs = 0;
  for (auto at = html.find("<svg"); at != std::string::npos; at = html.find("<svg", at + 1)) ++svgs;
  EXPECT_EQ(svgs, 3u);
  // Each picture's ids are its own: gnuplot's marker id appears once per picture, prefixed.
  for (const char* id : {"id='f1-gpPt7'", "id='f2-gpPt7'", "id='f3-gpPt7'"}) EXPECT_NE(html.find(id), std::string::npos) << id;
  EXPECT_EQ(html.find("id='gpPt7'"), std::string::npos);
  EXPECT_EQ(html.find("href='#gpPt"), std::string::npos);

  // Caller text is escaped.
  EXPECT_NE(html.find("Fit of &lt;damper&gt; &amp; spring"), std::string::npos);
  EXPECT_NE(html.find("a&lt;b &amp; c&gt;d"), std::string::npos);
  EXPECT_NE(html.find("a&lt;1&gt;"), std::string::npos);
  EXPECT_NE(html.find("x &lt; 3 &amp; y &gt; 2"), std::string::npos);
  EXPECT_EQ(html.find("<damper>"), std::string::npos);
  EXPECT_EQ(html.find("a<b & c>d"), std::string::npos);
  EXPECT_EQ(html.find("a<1>"), std::string::npos);
  expect_only_pictures(dir);
}

TEST(HtmlReport, RefusesToEmbedAnSvgThatReachesOutside) {
  EXPECT_EQ(inline_svg("<svg><script>alert(1)</script></svg>"), "");
  EXPECT_EQ(inline_svg("<svg><image href='http://example.org/x.png'/></svg>"), "");
  EXPECT_EQ(inline_svg("not a picture"), "");
  EXPECT_EQ(inline_svg("<?xml version=\"1.0\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\"><use xlink:href='#a'/></svg>"),
            "<svg ><use xlink:href='#a'/></svg>");
  EXPECT_EQ(inline_svg("<svg><g id='a' fill='url(#b)'/><use href=\"#a\"/><g id=\"b\"/></svg>", "f7-"),
            "<svg><g id='f7-a' fill='url(#f7-b)'/><use href=\"#f7-a\"/><g id=\"f7-b\"/></svg>");
  EXPECT_EQ(html_escape("<a href=\"x\">'&'</a>"), "&lt;a href=&quot;x&quot;&gt;&#39;&amp;&#39;&lt;/a&gt;");
}

}  // namespace

// Times print with the digits that tell samples apart: a record stamped in Unix seconds would
// otherwise print every sample and event as 1.733e+09.
TEST(TimeText, KeepsTheDigitsTheStepNeeds) {
  EXPECT_EQ(time_text(8.6, 0.01, 4), "8.6");        // as {:.4g}: ordinary records print as before
  EXPECT_EQ(time_text(49.1234, 0.01, 4), "49.12");
  EXPECT_EQ(time_text(0.0, 0.01, 4), "0");
  EXPECT_EQ(time_text(1732780829.99, 0.01, 4), "1732780829.99");
  EXPECT_EQ(time_text(1732780800.0, 0.01, 6), "1732780800");
  EXPECT_EQ(time_text(12345.67, 0.01, 4), "12345.67");
  EXPECT_EQ(time_text(2.5e6, 0.0, 4), "2.5e+06");    // no step: as before
  EXPECT_EQ(time_text(NAN, 0.01, 4), "nan");
}

}  // namespace sidc
