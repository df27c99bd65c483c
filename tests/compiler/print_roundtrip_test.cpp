// Property: printing a compiled model, parsing and compiling the print, and printing again gives
// the same text, for every golden model (normalized and integrated stages).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "compile_text.hpp"
#include "ir/print.hpp"

namespace sidc {
namespace {

std::vector<std::filesystem::path> golden_models() {
  std::vector<std::filesystem::path> paths;
  for (const char* dir : {"normalized", "integrated"})
    for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(SIDC_SOURCE_DIR) / "tests/golden" / dir))
      if (entry.path().extension() == ".sid") paths.push_back(entry.path());
  std::sort(paths.begin(), paths.end());
  return paths;
}

TEST(PrintRoundTrip, PrintParsePrintIsAFixedPoint) {
  const auto paths = golden_models();
  ASSERT_GE(paths.size(), 20u);
  for (const auto& path : paths) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    const auto first = testing::compile_text(text.str());
    if (!first.ok()) continue;  // cases that stop at a dump stage or fail on purpose
    for (const ir::Model* stage : {&*first.normalized, &*first.integrated}) {
      const std::string printed = print(*stage);
      const auto second = testing::compile_text(printed, {{}, "normalize"});
      ASSERT_TRUE(second.ok()) << path << "\n" << printed << "\n" << second.diagnostics.render_all();
      EXPECT_EQ(print(*second.normalized), printed) << path;
    }
  }
}

}  // namespace
}  // namespace sidc
