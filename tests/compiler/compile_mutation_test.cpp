// Property: no model text makes the compiler throw or crash. Every golden model is mutated at
// random (fixed seed) with the language's own tokens and compiled through every pass, with the
// integration forced to 0, 1, 2, 8 and auto; each compile must end in a result or diagnostics.
// The parser has its own mutation test (tests/grammar/robustness_test.cpp); this one reaches
// the passes behind it. Run it under `scripts/test.sh --sanitize` to catch memory errors too.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "ir/compiled_model.hpp"
#include "compiler/pipeline.hpp"
#include "ir/print.hpp"

namespace sidc {
namespace {

std::vector<std::string> golden_texts() {
  std::vector<std::filesystem::path> paths;
  for (const char* dir : {"normalized", "integrated", "bad"})
    for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(SIDC_SOURCE_DIR) / "tests/golden" / dir))
      if (entry.path().extension() == ".sid") paths.push_back(entry.path());
  std::sort(paths.begin(), paths.end());
  std::vector<std::string> texts;
  for (const auto& p : paths) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    if (s.str().size() < 20000) texts.push_back(s.str());
  }
  return texts;
}

// Pieces a mutation may insert: tokens of the language, including ones that stress the passes.
const std::vector<std::string> kPieces{
    "y", "y'", "y''", "x", "t", "t0", "tau", "pi", "a1", "a2", "c[1]", "c[k]", "0", "1", "2", "-1", "0.5", "1e300", "1e-300",
    "+", "-", "*", "/", "^", "(", ")", "[", "]", "=", ",", "<", "<=", ">", " and ", "'", "\n", " ", "sin(", "log(", "sqrt(",
    "abs(", "sign(", "der(", "int(", "y(0)", "y(t0)", "sum(k = 1..3, ", "^-1", "^0.5", "^40", "/(y - y)", "[y > 0]*",
    "set integrate = auto\n", "set constants = initial\n", "param ", "const g = 0\n", "input ", "output ", "1/0"};

std::string mutate(std::string text, std::mt19937& rng) {
  const int edits = 1 + static_cast<int>(rng() % 4);
  for (int e = 0; e < edits; ++e) {
    const std::size_t at = text.empty() ? 0 : rng() % (text.size() + 1);
    switch (rng() % 3) {
      case 0: text.insert(at, kPieces[rng() % kPieces.size()]); break;
      case 1:
        if (!text.empty()) text.erase(std::min(at, text.size() - 1), 1 + rng() % 6);
        break;
      default:
        if (!text.empty()) text[std::min(at, text.size() - 1)] = "y'*+-()[]=^0123a<>\n "[rng() % 20];
    }
  }
  return text;
}

// One shard of the mutations: 500 rounds from its own seed. Three shards (1500 rounds in all)
// are three tests, so that the sanitizer pass, where each compile is ten times slower, runs them
// side by side.
void mutate_and_compile(unsigned seed) {
  const auto texts = golden_texts();
  ASSERT_GE(texts.size(), 50u);
  std::mt19937 rng(seed);
  std::size_t compiled_ok = 0, rejected = 0;
  for (int round = 0; round < 500; ++round) {
    const std::string text = mutate(texts[rng() % texts.size()], rng);
    for (const char* request : {"", "0", "1", "2", "8", "auto"}) {
      CompileOptions options;
      if (*request) {
        ir::IntegrationRequest r;
        if (std::string(request) == "auto") r.count = ir::IntegrationRequest::Count::automatic;
        else r.times = std::stoi(request);
        options.integrate.override_request = r;
      }
      try {
        auto source = std::make_shared<const SourceFile>("mutated.sid", text);
        const CompileResult r = compile(source, options);
        if (r.ok()) {
          ++compiled_ok;
          // What compiles must print, serialize and read back.
          (void)print(*r.integrated);
          const auto j = to_json(compiled_model(source, *r.normalized, *r.integrated));
          std::string error;
          ASSERT_TRUE(compiled_model_from_json(j, "mutated.sidc.json", error)) << error << "\n" << text;
        } else {
          ++rejected;
          ASSERT_FALSE(r.diagnostics.render_all().empty()) << text;
        }
      } catch (const std::exception& ex) {
        FAIL() << "compile threw `" << ex.what() << "` (integrate " << request << ") on:\n" << text;
      }
    }
  }
  ::testing::Test::RecordProperty("compiled", static_cast<int>(compiled_ok));
  ::testing::Test::RecordProperty("rejected", static_cast<int>(rejected));
  EXPECT_GT(compiled_ok, 100u);  // the mutations must not all be rejected, or the passes go untested
  EXPECT_GT(rejected, 100u);
}

TEST(CompileMutation, NoMutatedModelMakesTheCompilerThrow) { mutate_and_compile(20261121); }
TEST(CompileMutation, NoMutatedModelMakesTheCompilerThrowShard2) { mutate_and_compile(20261122); }
TEST(CompileMutation, NoMutatedModelMakesTheCompilerThrowShard3) { mutate_and_compile(20261123); }

}  // namespace
}  // namespace sidc
