// From a real fit to pictures and the report: the path `sidc fit --plots DIR --report FILE` takes
// (the lead wires it in cli/). A correctly specified model leaves white residuals; a model with
// a term missing leaves residuals that the whiteness test flags; both reach the report.
//
// Relies on: compiler/pipeline.hpp (model text -> ir::Model), runtime/solve/fit, /usr/bin/gnuplot.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "compiler/pipeline.hpp"
#include "report/fit_figures.hpp"
#include "report/gnuplot_renderer.hpp"
#include "report/html_report.hpp"
#include "runtime/solve/fit.hpp"
#include "runtime/solve/residual_correlation.hpp"

namespace sidc {
namespace {

namespace fs = std::filesystem;

ir::Model compiled(const std::string& text) {
  const auto r = compile(std::make_shared<const SourceFile>("fit_report_test.sid", text), {});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return r.ok() ? *r.integrated : ir::Model{};
}

// x = 0.5 y' + 2 y + white noise, y a sum of sines: the equation holds up to the noise in x.
SampledRecord noisy_record(unsigned seed, double phase) {
  SampledRecord r;
  r.path = "synthetic_" + std::to_string(seed) + ".csv";
  r.step = 1e-2;
  std::mt19937 generator(seed);
  std::normal_distribution<double> noise(0, 0.05);
  for (std::size_t k = 0; k < 1500; ++k) {
    const double t = static_cast<double>(k) * r.step;
    const double y = std::sin(2 * t + phase) + 0.3 * std::sin(3.1 * t);
    const double dy = 2 * std::cos(2 * t + phase) + 0.93 * std::cos(3.1 * t);
    r.time.push_back(t);
    r.signals["y"].push_back(y);
    r.signals["x"].push_back(0.5 * dy + 2.0 * y + noise(generator));
  }
  return r;
}

ResidualCorrelationSummary analyse(const ir::Model& model, const std::vector<SampledRecord>& records,
                                   FitSummary* fitted) {
  auto result = fit(model, records, {});
  EXPECT_TRUE(std::holds_alternative<FitSummary>(result));
  if (!std::holds_alternative<FitSummary>(result)) return {};
  *fitted = std::get<FitSummary>(result);
  const auto segments = group_residuals(model, records, {}, *fitted, 0, {"x"});
  EXPECT_TRUE(segments.ok) << segments.message;
  EXPECT_EQ(segments.residuals.size(), records.size());  // one equation: one segment per record
  return residual_correlation(segments.residuals, segments.inputs, {});
}

TEST(FitReport, WhiteResidualsOfAGoodModelAndCorrelatedOnesOfAPoorOneReachTheReport) {
  const std::vector<SampledRecord> records = {noisy_record(1, 0.3), noisy_record(2, 1.1)};
  FitSummary good_fit, poor_fit;
  const auto good = analyse(compiled("input x\noutput y\nparam a1, a2\na1*y' + a2*y = x\n"), records, &good_fit);
  const auto poor = analyse(compiled("input x\noutput y\nparam a1\na1*y' = x\n"), records, &poor_fit);
  ASSERT_TRUE(good.is_usable()) << good.message;
  ASSERT_TRUE(poor.is_usable()) << poor.message;
  EXPECT_EQ(good.n, 2 * good_fit.groups[0].records[0].rows);
  EXPECT_TRUE(good.autocorrelation.white) << good.brief_report();
  EXPECT_FALSE(poor.residuals_white) << poor.brief_report();
  EXPECT_FALSE(poor.autocorrelation.white) << "the missing term 2*y leaves a smooth residual";

  const fs::path dir = fs::path(SIDC_REPORT_TEST_DIR) / "fit_report";
  fs::remove_all(dir);
  ReportContent content;
  content.title = "sidc fit report";
  content.model_name = "first_order";
  content.source_file = "fit_report_test.sid";
  content.model_text = "input x\noutput y\nparam a1, a2\na1*y' + a2*y = x";
  content.settings = {{"derivatives", "moving arc, 7 points, cubic (default)"}};
  for (const auto& r : records) content.records.push_back(r.path);
  for (const auto* which : {&good, &poor}) {
    const auto& fitted = which == &good ? good_fit : poor_fit;
    ReportGroup group;
    group.title = which == &good ? "Equation 1 (a1*y' + a2*y = x)" : "Equation 1 (a1*y' = x)";
    fill_group_from(fitted.groups[0].summary, 0.95, &group);
    group.residual_verdicts.push_back(which->verdict);
    const std::string tag = which == &good ? "good" : "poor";
    for (auto figure : {residual_autocorrelation_figure(*which, tag), residual_cross_correlation_figure(*which, 0, tag)}) {
      const auto rendered = render_figure(figure, dir.string(), {});
      ASSERT_TRUE(rendered.ok()) << rendered.message;
      std::string why;
      group.figures.push_back(report_figure_from_file(rendered.files.at(0), figure.title, &why));
      ASSERT_FALSE(group.figures.back().svg.empty()) << why;
    }
    content.groups.push_back(std::move(group));
  }
  const auto written = write_html_report(content, (dir / "report.html").string());
  ASSERT_TRUE(written.ok) << written.message;
  std::ifstream in(dir / "report.html");
  std::stringstream html;
  html << in.rdbuf();
  EXPECT_NE(html.str().find("residuals look white"), std::string::npos);
  EXPECT_NE(html.str().find("residuals autocorrelated at lags 1"), std::string::npos);
  EXPECT_NE(html.str().find(">a2<"), std::string::npos);
}

TEST(FitReport, StreamedAndDenseFitsGiveTheSameResidualSegments) {
  const std::vector<SampledRecord> records = {noisy_record(1, 0.3), noisy_record(2, 1.1)};
  const ir::Model model = compiled("input x\noutput y\nparam a1, a2\na1*y' + a2*y = x\n");
  FitOptions dense_options, streamed_options;
  streamed_options.stream_above_entries = 0;  // every group streamed: residuals by a second pass
  streamed_options.stream_block_rows = 7;
  auto dense = fit(model, records, dense_options);
  auto streamed = fit(model, records, streamed_options);
  ASSERT_TRUE(std::holds_alternative<FitSummary>(dense));
  ASSERT_TRUE(std::holds_alternative<FitSummary>(streamed));
  const auto a = group_residuals(model, records, dense_options, std::get<FitSummary>(dense), 0, {"x"});
  const auto b = group_residuals(model, records, streamed_options, std::get<FitSummary>(streamed), 0, {"x"});
  ASSERT_TRUE(a.ok) << a.message;
  ASSERT_TRUE(b.ok) << b.message;
  ASSERT_EQ(a.residuals.size(), 2u);  // one segment per record, never joined
  ASSERT_EQ(b.residuals.size(), 2u);
  for (std::size_t s = 0; s < 2; ++s) {
    ASSERT_EQ(a.residuals[s].size(), b.residuals[s].size());
    for (std::size_t i = 0; i < a.residuals[s].size(); ++i) EXPECT_NEAR(a.residuals[s][i], b.residuals[s][i], 1e-9);
    EXPECT_EQ(a.inputs[0].segments[s], b.inputs[0].segments[s]);
  }
  EXPECT_FALSE(a.truncated);

  const auto first_ten = group_residuals(model, records, dense_options, std::get<FitSummary>(dense), 0, {"x"}, 10);
  ASSERT_TRUE(first_ten.ok);
  EXPECT_TRUE(first_ten.truncated);
  EXPECT_EQ(first_ten.residuals.at(0).size(), 10u);

  const auto missing = group_residuals(model, records, dense_options, std::get<FitSummary>(dense), 0, {"z"});
  EXPECT_FALSE(missing.ok);
  EXPECT_NE(missing.message.find("no signal `z`"), std::string::npos) << missing.message;
  const auto no_group = group_residuals(model, records, dense_options, std::get<FitSummary>(dense), 3, {"x"});
  EXPECT_FALSE(no_group.ok);
}

}  // namespace
}  // namespace sidc
