// The pictures and report of issue 5, made by the sidc binary for the thesis example exactly as a
// user asks for them: `sidc fit quasi_linear.sid --plots DIR --report DIR/report.html`.
//
// Relies on: the sidc binary (SIDC_BINARY), gnuplot (installed by scripts/setup.sh), the example
// in examples/thesis-4-1 (its `plot damper(y')`/`plot spring(y)` statements and the exact
// derivatives Appendix A prints). Guarantees: each figure the thesis has a counterpart for is
// drawn as SVG and PNG, each file is a real picture (PNG signature, an SVG with drawn paths), and
// the report embeds every SVG and refers to no other file.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/shell.hpp"

namespace {

namespace fs = std::filesystem;
using sidc::testing::read_text;
using sidc::testing::shell_quoted;

// A fresh work folder holding the example's model and record, as a user has them.
fs::path example_copy(const std::string& name) {
  const fs::path work = fs::path(SIDC_THESIS_WORK_DIR) / name;
  fs::remove_all(work);
  fs::create_directories(work);
  const fs::path examples(SIDC_THESIS_EXAMPLE_DIR);
  fs::copy_file(examples / "appendix_a.csv", work / "appendix_a.csv");
  fs::copy_file(examples / "quasi_linear.sid", work / "quasi_linear.sid");
  return work;
}

TEST(ThesisPictures, EveryFigureIsDrawnAndTheReportEmbedsThem) {
  const fs::path work = example_copy("pictures");
  const fs::path pictures = work / "pictures", report = work / "report.html", log = work / "fit.log";
  const std::string command = "cd " + shell_quoted(work) + " && " + shell_quoted(SIDC_BINARY) + " fit quasi_linear.sid --plots " +
                              shell_quoted(pictures) + " --report " + shell_quoted(report) + " >" + shell_quoted(log) + " 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command << "\n" << read_text(log);

  // Figs. 4-2.5/4-2.6, 4-2.7, 4-1.13/4-1.14 (twice), 4-1.11 (twice), 4-1.8/4-1.9, 4-1.7, and the
  // residual tests.
  const std::vector<std::string> stems{"simulated_y",          "error_y",
                                       "function_damper",      "function_spring",
                                       "function_error_damper", "function_error_spring",
                                       "derivative_error_y",   "phase_plane_y",
                                       "residual_autocorrelation_1", "residual_cross_x_1"};
  const std::string html = read_text(report);
  EXPECT_GT(html.size(), 20000u);
  for (const auto& stem : stems) {
    const std::string png = read_text(pictures / (stem + ".png"));
    ASSERT_GT(png.size(), 5000u) << stem;
    EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << stem;
    const std::string svg = read_text(pictures / (stem + ".svg"));
    EXPECT_NE(svg.find("<svg"), std::string::npos) << stem;
    EXPECT_NE(svg.find("<path"), std::string::npos) << stem;
  }
  // One inline <svg> per figure, and nothing fetched from elsewhere.
  std::size_t count = 0;
  for (std::size_t at = html.find("<svg"); at != std::string::npos; at = html.find("<svg", at + 1)) ++count;
  EXPECT_EQ(count, stems.size());
  EXPECT_EQ(html.find("src="), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_NE(html.find("quasi_linear"), std::string::npos);
  EXPECT_NE(html.find("G(a)"), std::string::npos);
}

TEST(ThesisPictures, AFailingFigureLeavesNoReportBehind) {
  const fs::path work = example_copy("pictures_unwritable");
  // --plots names a regular file: the folder cannot be made, which is found before the fit.
  { std::ofstream(work / "taken") << "x"; }
  const fs::path log = work / "fit.log";
  const std::string command = "cd " + shell_quoted(work) + " && " + shell_quoted(SIDC_BINARY) +
                              " fit quasi_linear.sid --plots taken --report report.html >" + shell_quoted(log) + " 2>&1";
  EXPECT_NE(std::system(command.c_str()), 0);
  EXPECT_NE(read_text(log).find("error: `--plots taken` cannot be written: it is a file, not a directory"), std::string::npos) << read_text(log);
  EXPECT_EQ(read_text(log).find("sidc fit: model"), std::string::npos) << "the fit ran before the output was checked";
  EXPECT_FALSE(fs::exists(work / "report.html"));
}

// A run that cannot draw leaves the previous run's pictures, manifest and report as they were:
// pictures are drawn in a private folder under $TMPDIR and only a whole set replaces the old one
// (here $TMPDIR does not exist, so the second run fails before it draws anything).
TEST(ThesisPictures, AFailedRunLeavesThePreviousPicturesAsTheyWere) {
  const fs::path work = example_copy("pictures_kept");
  const std::string fit = shell_quoted(SIDC_BINARY) + " fit quasi_linear.sid --plots pictures --report report.html";
  const fs::path log = work / "fit.log";
  ASSERT_EQ(std::system(("cd " + shell_quoted(work) + " && " + fit + " >" + shell_quoted(log) + " 2>&1").c_str()), 0) << read_text(log);
  std::vector<std::pair<fs::path, std::string>> before;
  for (const auto& entry : fs::directory_iterator(work / "pictures")) before.emplace_back(entry.path(), read_text(entry.path()));
  before.emplace_back(work / "report.html", read_text(work / "report.html"));
  ASSERT_GT(before.size(), 10u);

  const std::string again = "cd " + shell_quoted(work) + " && TMPDIR=" + shell_quoted(work / "no-such-folder") + " " + fit + " >" +
                            shell_quoted(log) + " 2>&1";
  EXPECT_NE(std::system(again.c_str()), 0);
  EXPECT_NE(read_text(log).find("no-such-folder/sidc-figures.XXXXXX"), std::string::npos) << read_text(log);
  EXPECT_NE(read_text(log).find("hint: set TMPDIR to a folder you can write to"), std::string::npos) << read_text(log);
  std::size_t now = 0;
  for (const auto& entry : fs::directory_iterator(work / "pictures")) {
    (void)entry;
    ++now;
  }
  EXPECT_EQ(now + 1, before.size());
  for (const auto& [path, content] : before) EXPECT_EQ(read_text(path), content) << path;
}

}  // namespace
