// The compiled model file (ir/compiled_model.hpp) against its documentation: every golden
// model compiles to JSON that validates against docs/compiled-model.schema.json, compiling twice
// gives the same bytes, reading a file back and writing it again gives the same JSON, and a
// broken file is refused with a message rather than a crash.
//
// The golden models are compiled as they are and also with every equation integrated once,
// twice and `auto`, so that integrals, tau and integration constants (fitted and initial) appear;
// one more model written here covers the factor kinds and settings no golden model has. The
// validator (json_schema.hpp) is itself checked on small schemas, and the schema on documents
// broken on purpose, so that a pass means the schema was applied.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <sstream>

#include "ir/compiled_model.hpp"
#include "compiler/load_model.hpp"
#include "compiler/pipeline.hpp"
#include "json_schema.hpp"

namespace sidc {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

const json& schema() {
  static const json parsed = json::parse(read_text(fs::path(SIDC_SOURCE_DIR) / "docs/compiled-model.schema.json"));
  return parsed;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  return out;
}

// Covers what no golden model has: power and window_start factors, an initial value at a given
// time, every setting away from its default, a constant, column bindings out of name order, and
// equations integrated differently (the first twice with initial values, the second not at all).
const char* const kEveryKindModel = R"(model every_kind
input x
input u = 2*sin(t) + 1
output y, z
param a1, a2, a3, a4, a5, a6, a7, a8
const g = 9.81
data "run.csv" (y = "disp", t = "time", x = "force", z = zz)
data "run2.csv"
set derivative = savgol(9, 4)
set second_derivative = direct
set edges = shorten
set integration = trapezoid
set smooth_before_integration = savgol(5, 2)
set from = 0.1
set to = 2.5
set every = 2
set step = 0.01
set estimator = iv
set integrate = 2
set constants = initial
a1*y' + a2*(y + 1)^-1 + a3*(y^2 + 1)^0.5 + a4*y(0.5) + a5*t0*y + a6*tau*z + a7*exp(z)*[x > 1 and x < 3] = g*x + u + y'(0)
set integrate = 0
z' = a1*z + a8*der([z > 0]*z, 1) + t*x
)";

struct Case {
  std::string name;  // for messages: the model file and the integration asked for
  std::shared_ptr<const SourceFile> source;
  CompileOptions options;
};

std::vector<Case> cases() {
  std::vector<std::pair<std::string, std::string>> models;  // source name, text
  for (const char* dir : {"normalized", "integrated"}) {
    std::vector<fs::path> paths;
    for (const auto& entry : fs::directory_iterator(fs::path(SIDC_SOURCE_DIR) / "tests/golden" / dir))
      if (entry.path().extension() == ".sid") paths.push_back(entry.path());
    std::sort(paths.begin(), paths.end());
    for (const auto& p : paths) models.emplace_back("tests/golden/" + std::string(dir) + "/" + p.filename().string(), read_text(p));
  }
  models.emplace_back("every_kind.sid", kEveryKindModel);

  std::vector<std::pair<std::string, std::optional<ir::IntegrationRequest>>> integrations{{"as written", std::nullopt}};
  for (int n : {1, 2}) integrations.push_back({"--integrate " + std::to_string(n), ir::IntegrationRequest{{}, n, {}, false, {}}});
  integrations.push_back({"--integrate auto", ir::IntegrationRequest{ir::IntegrationRequest::Count::automatic, 0, {}, false, {}}});

  std::vector<Case> out;
  for (const auto& [name, text] : models)
    for (const auto& [how, request] : integrations) {
      CompileOptions options;
      options.integrate.override_request = request;
      out.push_back({name + " (" + how + ")", std::make_shared<const SourceFile>(name, text), options});
    }
  return out;
}

// nullopt for models that fail on purpose or stop early (none of the golden models should, but
// the golden folders may gain such cases; the count below keeps the test from passing empty).
std::optional<CompiledModel> compiled(const Case& c) {
  // A fresh SourceFile each time, as a second `sidc compile` run would have.
  auto source = std::make_shared<const SourceFile>(c.source->name, c.source->text);
  CompileResult r = compile(source, c.options);
  if (!r.ok() || !r.normalized || !r.integrated) return std::nullopt;
  return compiled_model(source, *r.normalized, *r.integrated);
}

// The file as `sidc compile` writes it, read as `sidc fit` reads it.
std::string file_text(const CompiledModel& c) { return to_json(c).dump(1) + "\n"; }
json as_read(const CompiledModel& c) { return json::parse(file_text(c)); }

// Where two long texts part, as `line N: `first` / `second``, for a readable failure.
std::string first_difference(const std::string& a, const std::string& b) {
  std::istringstream in_a(a), in_b(b);
  std::string line_a, line_b;
  for (int line = 1;; ++line) {
    const bool more_a = static_cast<bool>(std::getline(in_a, line_a)), more_b = static_cast<bool>(std::getline(in_b, line_b));
    if (!more_a && !more_b) return "no difference";
    if (!more_a || !more_b || line_a != line_b)
      return "line " + std::to_string(line) + ": `" + (more_a ? line_a : "(end)") + "` / `" + (more_b ? line_b : "(end)") + "`";
  }
}

void collect_factor_kinds(const json& j, std::set<std::string>& kinds) {
  if (j.is_object()) {
    if (j.contains("kind") && j.contains("power")) kinds.insert(j.at("kind").get<std::string>());
    for (const auto& [key, value] : j.items()) collect_factor_kinds(value, kinds);
  } else if (j.is_array()) {
    for (const auto& value : j) collect_factor_kinds(value, kinds);
  }
}

// ---- the validator on small schemas --------------------------------------------------------------

TEST(JsonSchemaValidator, AppliesEachKeyword) {
  const json s = json::parse(R"({
    "type": "object", "additionalProperties": false, "required": ["n", "kind"],
    "properties": {
      "n": {"type": "integer", "minimum": 1, "maximum": 9},
      "kind": {"enum": ["a", "b"]},
      "tag": {"const": "x"},
      "maybe": {"type": ["number", "null"], "exclusiveMinimum": 0},
      "name": {"type": "string", "minLength": 2, "pattern": "^[a-z]+$"},
      "list": {"type": "array", "minItems": 1, "items": {"$ref": "#/$defs/small"}},
      "map": {"type": "object", "additionalProperties": {"type": "string"}},
      "one": {"oneOf": [{"type": "integer"}, {"type": "number", "minimum": 0}]},
      "any": {"anyOf": [{"type": "null"}, {"$ref": "#/$defs/small"}]}
    },
    "$defs": {"small": {"type": "integer", "maximum": 3}}
  })");
  ASSERT_TRUE(testing::unsupported_keywords(s).empty()) << joined(testing::unsupported_keywords(s));
  auto errors = [&](const char* document) { return testing::validate_against_schema(s, json::parse(document)); };

  EXPECT_TRUE(errors(R"({"n": 3, "kind": "a"})").empty());
  EXPECT_TRUE(errors(R"({"n": 3.0, "kind": "b", "tag": "x", "maybe": null, "name": "ab", "list": [1, 3], "map": {"k": "v"},
                         "one": 0.5, "any": 2})").empty());
  EXPECT_TRUE(errors(R"({"n": 3, "kind": "a", "maybe": 0.25, "one": -2, "any": null})").empty());

  const std::vector<std::pair<const char*, const char*>> broken{
      {R"([])", "(root): expected"},
      {R"({"kind": "a"})", "required property \"n\""},
      {R"({"n": 0, "kind": "a"})", "/n: 0"},
      {R"({"n": 10, "kind": "a"})", "above the maximum"},
      {R"({"n": 2.5, "kind": "a"})", "/n: expected \"integer\""},
      {R"({"n": 1, "kind": "c"})", "/kind: expected one of"},
      {R"({"n": 1, "kind": "a", "tag": "y"})", "/tag: expected \"x\""},
      {R"({"n": 1, "kind": "a", "maybe": 0})", "/maybe: 0 is not above 0"},
      {R"({"n": 1, "kind": "a", "maybe": "1"})", "/maybe: expected [\"number\",\"null\"]"},
      {R"({"n": 1, "kind": "a", "name": "a"})", "/name: shorter than 2"},
      {R"({"n": 1, "kind": "a", "name": "aB"})", "does not match the pattern"},
      {R"({"n": 1, "kind": "a", "list": []})", "/list: fewer than 1 items"},
      {R"({"n": 1, "kind": "a", "list": [1, 4]})", "/list/1: 4 is above the maximum 3"},
      {R"({"n": 1, "kind": "a", "map": {"k/~": 1}})", "/map/k~1~0: expected \"string\""},
      {R"({"n": 1, "kind": "a", "one": 2})", "exactly one expected"},   // an integer is also a number >= 0
      {R"({"n": 1, "kind": "a", "one": -0.5})", "matches none of the 2 alternatives of oneOf"},
      {R"({"n": 1, "kind": "a", "any": 7})", "/any: 7 is above the maximum 3"},  // the nearest alternative's reason
      {R"({"n": 1, "kind": "a", "extra": true})", "unexpected property \"extra\""},
  };
  for (const auto& [document, expected] : broken) {
    const std::string all = joined(errors(document));
    EXPECT_NE(all.find(expected), std::string::npos) << document << " gave:\n" << all;
  }
}

TEST(JsonSchemaValidator, ReportsWhatItDoesNotImplement) {
  const auto problems = testing::unsupported_keywords(json::parse(R"({"type": "object",
      "properties": {"a": {"if": {}, "then": {}}, "b": {"$ref": "#/$defs/missing"}, "c": {"$ref": "other.json"}}})"));
  const std::string all = joined(problems);
  EXPECT_NE(all.find("/properties/a: keyword \"if\""), std::string::npos) << all;
  EXPECT_NE(all.find("\"#/$defs/missing\""), std::string::npos) << all;
  EXPECT_NE(all.find("\"other.json\""), std::string::npos) << all;
}

// ---- the schema ------------------------------------------------------------------------------------

TEST(CompiledModelSchema, UsesOnlyWhatTheValidatorImplements) {
  const auto problems = testing::unsupported_keywords(schema());
  EXPECT_TRUE(problems.empty()) << joined(problems);
}

TEST(CompiledModelSchema, EveryGoldenModelValidates) {
  std::size_t validated = 0;
  std::set<std::string> kinds, origins;
  for (const auto& c : cases()) {
    const auto model = compiled(c);
    if (!model) continue;
    const json j = as_read(*model);
    const auto errors = testing::validate_against_schema(schema(), j);
    EXPECT_TRUE(errors.empty()) << c.name << ":\n" << joined(errors);
    collect_factor_kinds(j, kinds);
    for (const auto& p : j.at("parameters")) origins.insert(p.at("origin").get<std::string>());
    ++validated;
  }
  // 30 golden models and one written here, 4 ways each; a few golden cases stop early on purpose.
  EXPECT_GE(validated, 100u);
  // The corpus reaches every factor kind a file can hold, so each kind's schema has been applied.
  EXPECT_EQ(kinds, (std::set<std::string>{"signal", "initial_value", "window_start", "time", "elapsed", "function", "power",
                                          "derivative", "integral", "guard", "parameter"}));
  EXPECT_EQ(origins, (std::set<std::string>{"declared", "implicit", "integration_constant"}));
}

// Inputs declared held or linear (the cases of tests/golden/held/, which the corpus above leaves
// out since some are in weak form, whose test functions it does not count): the file gives each
// such input its hold, validates against the schema, and reads back with the same holds; a smooth
// signal's entry has no `hold` at all.
TEST(CompiledModelSchema, HeldInputsValidateAndReadBack) {
  std::size_t models = 0, holds = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(SIDC_SOURCE_DIR) / "tests/golden/held")) {
    if (entry.path().extension() != ".sid") continue;
    const std::string name = entry.path().filename().string();
    const auto model = compiled(Case{name, std::make_shared<const SourceFile>(name, read_text(entry.path())), {}});
    ASSERT_TRUE(model.has_value()) << name;
    const json j = as_read(*model);
    const auto errors = testing::validate_against_schema(schema(), j);
    EXPECT_TRUE(errors.empty()) << name << ":\n" << joined(errors);
    std::string error;
    const auto read = compiled_model_from_json(j, name + ".sidc.json", error);
    ASSERT_TRUE(read.has_value()) << name << ": " << error;
    for (const auto& s : j.at("signals")) {
      const auto signal = s.at("name").get<std::string>();
      const ir::Signal* written = model->normalized.signal(signal);
      const ir::Signal* back = read->normalized.signal(signal);
      ASSERT_TRUE(written && back) << name << ": " << signal;
      EXPECT_EQ(back->hold, written->hold) << name << ": " << signal;
      if (written->hold == ir::Signal::Hold::smooth) {
        EXPECT_FALSE(s.contains("hold")) << name << ": " << signal;
      } else {
        EXPECT_EQ(s.value("hold", ""), ir::to_string(written->hold)) << name << ": " << signal;
        ++holds;
      }
    }
    ++models;
  }
  EXPECT_GE(models, 6u);
  EXPECT_GE(holds, 7u);
}

json van_der_pol() {
  const fs::path path = fs::path(SIDC_SOURCE_DIR) / "tests/golden/integrated/thesis_2_2_8_van_der_pol_once.sid";
  Case c{"van der pol", std::make_shared<const SourceFile>("thesis_2_2_8_van_der_pol_once.sid", read_text(path)), {}};
  c.options.integrate.override_request = ir::IntegrationRequest{{}, 1, {}, false, {}};
  const auto model = compiled(c);
  EXPECT_TRUE(model.has_value());
  return model ? as_read(*model) : json::object();
}

TEST(CompiledModelSchema, RejectsDocumentsBrokenOnPurpose) {
  const json good = van_der_pol();
  ASSERT_TRUE(testing::validate_against_schema(schema(), good).empty());
  const json::json_pointer first_factor("/equations/0/operations/0/operation/terms/0/factors/0");
  ASSERT_TRUE(good.contains(first_factor));

  struct Breakage {
    const char* what;
    std::function<void(json&)> apply;
    const char* expected;  // in the validator's report
  };
  const std::vector<Breakage> breakages{
      {"missing required field", [](json& j) { j.erase("version"); }, "(root): the required property \"version\" is missing"},
      {"wrong enum", [](json& j) { j["settings"]["edges"] = "chop"; }, "/settings/edges: expected one of"},
      {"extra property", [](json& j) { j["comment"] = "hand-edited"; }, "unexpected property \"comment\""},
      {"extra property deep down", [&](json& j) { j[first_factor]["note"] = 1; }, "unexpected property \"note\""},
      {"wrong format", [](json& j) { j["format"] = "sidc-model"; }, "/format: expected \"sidc-compiled-model\""},
      {"other version", [](json& j) { j["version"] = 1; }, "/version: expected 2"},
      {"unknown factor kind", [&](json& j) { j[first_factor]["kind"] = "spline"; }, "matches none of the 12 alternatives"},
      {"zero power", [&](json& j) { j[first_factor]["power"] = 0; }, "/power"},
      {"zero denominator", [](json& j) { j["equations"][0]["known"]["terms"][0]["coefficient"]["den"] = 0; }, "/den: 0 is below"},
      {"an infinite coefficient (written as null)", [](json& j) { j["equations"][0]["known"]["terms"][0]["coefficient"] = {{"real", nullptr}}; },
       "/coefficient: matches none"},
      {"signal without span", [](json& j) { j["signals"][0]["span"] = nullptr; }, "/signals/0/span: expected \"object\""},
      {"unknown hold", [](json& j) { j["signals"][0]["hold"] = "step"; }, "/signals/0/hold: expected one of"},
      {"hold written for a smooth signal", [](json& j) { j["signals"][0]["hold"] = "smooth"; }, "/signals/0/hold: expected one of"},
      {"bad hash", [](json& j) { j["source"]["hash"] = "395bc80f8c3f2a86"; }, "/source/hash"},
      {"integration constant without its equation", [](json& j) {
         for (auto& p : j["parameters"]) if (p["origin"] == "integration_constant") p["equation"] = -1;
       }, "/parameters/3: matches none of the 2 alternatives of oneOf"},
      {"text where the normalized form holds a tree", [](json& j) { j["normalized"][0]["known"] = "x"; },
       "/normalized/0/known: expected \"object\""},
      {"plot without operations", [](json& j) {
         j["plots"] = json::array({{{"name", "f"}, {"text", "plot f(y) = 1"}, {"span", j["signals"][0]["span"]}, {"signal", "y"},
                                    {"order", 0}, {"operations", json::array()}, {"rest", j["equations"][0]["known"]}, {"truth", nullptr}}});
       }, "/plots/0/operations"},
  };
  for (const auto& b : breakages) {
    json broken = good;
    b.apply(broken);
    const std::string all = joined(testing::validate_against_schema(schema(), broken));
    EXPECT_NE(all.find(b.expected), std::string::npos) << b.what << ": expected a report containing `" << b.expected << "`, got:\n" << all;
  }
}

// ---- the writer -------------------------------------------------------------------------------------

TEST(CompiledModelFile, CompilingTwiceGivesIdenticalBytes) {
  std::size_t compared = 0;
  for (const auto& c : cases()) {
    const auto first = compiled(c);
    if (!first) continue;
    // Shift the heap between the runs, so that an order taken from addresses would show.
    std::vector<std::unique_ptr<char[]>> ballast;
    for (std::size_t i = 0; i < 64; ++i) ballast.emplace_back(new char[16 + 24 * i]);
    const auto second = compiled(c);
    ASSERT_TRUE(second.has_value()) << c.name;
    const std::string a = file_text(*first), b = file_text(*second);
    EXPECT_TRUE(a == b) << c.name << ": " << first_difference(a, b);
    ++compared;
  }
  EXPECT_GE(compared, 100u);
}

TEST(CompiledModelFile, HashIsFnv1a64OfTheSourceText) {
  // Reference values of 64-bit FNV-1a (offset basis 0xcbf29ce484222325, prime 0x100000001b3).
  EXPECT_EQ(source_hash(""), "fnv1a64:cbf29ce484222325");
  EXPECT_EQ(source_hash("a"), "fnv1a64:af63dc4c8601ec8c");
  EXPECT_EQ(source_hash("foobar"), "fnv1a64:85944171f73967e8");
  const json j = van_der_pol();
  EXPECT_EQ(j.at("source").at("hash"), source_hash(j.at("source").at("text").get<std::string>()));
}

// ---- the reader -------------------------------------------------------------------------------------

// Reading a file and writing it again loses nothing a reader can use. Compared as JSON values,
// as `sidc fit` reads them: member order is not kept by its reader (nlohmann::json sorts
// members), which matters only for `bindings`, the one object written in declaration order, and
// there only to the eye (bindings are looked up by name). `normalized` is left out: it is text
// for people, and the reader does not read it back. Both reported to the lead.
TEST(CompiledModelFile, ReadingBackAndWritingAgainGivesTheSameJson) {
  std::size_t compared = 0;
  for (const auto& c : cases()) {
    const auto model = compiled(c);
    if (!model) continue;
    json written = as_read(*model);
    std::string error;
    const auto read = compiled_model_from_json(written, c.name + ".sidc.json", error);
    ASSERT_TRUE(read.has_value()) << c.name << ": " << error;
    json rewritten = as_read(*read);
    written.erase("normalized");
    rewritten.erase("normalized");
    EXPECT_TRUE(written == rewritten) << c.name << ": " << first_difference(written.dump(1), rewritten.dump(1));
    ++compared;
  }
  EXPECT_GE(compared, 100u);
}

// A plot entry of the model in `j`, against `signal` differentiated `order` times, made of its
// first equation's first operation (for breaking on purpose).
json plot_of(const json& j, const std::string& signal, int order) {
  return {{"name", "f"}, {"text", "plot f"}, {"span", j["signals"][0]["span"]}, {"signal", signal}, {"order", order},
          {"operations", json::array({j["equations"][0]["operations"][0]})}, {"rest", j["equations"][0]["known"]}, {"truth", nullptr}};
}

TEST(CompiledModelFile, ReaderRefusesBrokenFilesWithAMessage) {
  const json good = van_der_pol();
  std::string error;
  ASSERT_TRUE(compiled_model_from_json(good, "m.sidc.json", error).has_value()) << error;
  const json::json_pointer first_factor("/equations/0/operations/0/operation/terms/0/factors/0");
  const json::json_pointer first_coefficient("/equations/0/known/terms/0/coefficient");

  struct Breakage {
    const char* what;
    std::function<void(json&)> apply;
    std::vector<const char*> expected;  // each in the message
  };
  const std::vector<Breakage> breakages{
      {"wrong format name", [](json& j) { j["format"] = "something-else"; }, {"m.sidc.json", "not a compiled sidc model"}},
      {"not an object", [](json& j) { j = json::array({1, 2}); }, {"m.sidc.json"}},
      {"wrong version", [](json& j) { j["version"] = 1; }, {"m.sidc.json", "format 1", "reads format 2"}},
      {"version not a number", [](json& j) { j["version"] = "1"; }, {"m.sidc.json", "compile the model again"}},
      {"unknown factor kind", [&](json& j) { j[first_factor]["kind"] = "spline"; }, {"unknown factor kind `spline`"}},
      {"a test function outside the weak form", [&](json& j) { j[first_factor] = {{"kind", "test_function"}, {"order", 1}, {"power", 1}}; },
       {"test function `phi_j`", "not of the weak form"}},
      {"a weak equation's term without a test function", [](json& j) { j["equations"][0]["weak"] = true; },
       {"without exactly one test function"}},
      {"a test function of an order the weak form never writes", [&](json& j) {
         j["equations"][0]["weak"] = true;
         for (auto* s : {&j["equations"][0]["known"], &j["equations"][0]["operations"][0]["operation"]})
           for (auto& t : (*s)["terms"]) t["factors"].push_back({{"kind", "test_function"}, {"order", 40}, {"power", 1}});
       }, {"power or order the weak form never writes"}},
      {"a test function in the normalized equations", [](json& j) {
         j["normalized"][0]["known"]["terms"][0]["factors"].push_back({{"kind", "test_function"}, {"order", 0}, {"power", 1}});
       }, {"test function `phi_j` in the normalized equations"}},
      {"missing field", [](json& j) { j["equations"][0].erase("known"); }, {"m.sidc.json", "known", "compile the model again"}},
      {"missing field deep down", [&](json& j) { j[first_factor].erase("power"); }, {"power"}},
      {"negative denominator", [&](json& j) { j[first_coefficient] = {{"num", 1}, {"den", -2}}; }, {"denominator"}},
      {"zero denominator", [&](json& j) { j[first_coefficient] = {{"num", 1}, {"den", 0}}; }, {"denominator"}},
      {"a null real (what an infinite coefficient is written as)", [&](json& j) { j[first_coefficient] = {{"real", nullptr}}; },
       {"m.sidc.json", "compile the model again"}},
      {"operation of an undeclared parameter", [](json& j) { j["equations"][0]["operations"][0]["parameter"] = "b9"; },
       {"undeclared parameter"}},
      {"a negative derivative order", [&](json& j) {
         j[first_factor]["kind"] = "signal", j[first_factor]["name"] = "y", j[first_factor]["order"] = -2;
       }, {"derivative order of -2"}},
      {"a plot against a negative derivative", [](json& j) { j["plots"] = json::array({plot_of(j, "y", -1)}); }, {"plot", "order -1"}},
      {"a plot of an undeclared signal", [](json& j) { j["plots"] = json::array({plot_of(j, "z", 1)}); }, {"undeclared signal `z`"}},
      {"an exact derivative of order 0", [](json& j) {
         j["data"] = json::array({{{"path", "r.csv"}, {"bindings", json::object()},
                                   {"exact_derivatives", json::array({{{"signal", "y"}, {"order", 0}, {"column", "v"}}})}}});
       }, {"exact derivative of order 0"}},
      {"an exact derivative of an undeclared signal", [](json& j) {
         j["data"] = json::array({{{"path", "r.csv"}, {"bindings", json::object()},
                                   {"exact_derivatives", json::array({{{"signal", "q"}, {"order", 1}, {"column", "v"}}})}}});
       }, {"undeclared signal `q`"}},
      {"weights that are not a sum", [](json& j) { j["weights_expression"] = {{"expression", 3}, {"span", nullptr}}; },
       {"m.sidc.json", "compile the model again"}},
      {"an integral nested 300 deep (refused at level 257, before the recursion gets deep)", [](json& j) {
         // Written as text with each nested value last, so that building it is linear here too.
         std::string text = R"({"text": "y", "terms": [{"coefficient": {"num": 1, "den": 1}, "span": null, "factors": [{"kind": "signal", "name": "y", "order": 0, "power": 1}]}]})";
         std::string open, close;
         for (int k = 0; k < 300; ++k) {
           open += R"J({"text": "int(...)", "terms": [{"coefficient": {"num": 1, "den": 1}, "span": null, "factors": [{"kind": "integral", "power": 1, "argument": )J";
           close += "}]}]}";
         }
         j["equations"][0]["operations"][0]["operation"] = json::parse(open + text + close);
       }, {"nested more than 256 levels deep"}},
      // Found by the compiled-model fuzz target in CI's sanitizer pass: a float where an integer
      // belongs was converted to int64, which is undefined behaviour.
      {"a numerator of 1e83", [&](json& j) { j[first_coefficient] = {{"num", 1e83}, {"den", 1}}; }, {"`num` is ", ", not an integer that fits"}},
      {"a denominator of 2.5", [&](json& j) { j[first_coefficient] = {{"num", 1}, {"den", 2.5}}; }, {"`den` is ", ", not an integer that fits"}},
      {"a power of 1e83", [&](json& j) { j[first_factor]["power"] = 1e83; }, {"`power` is ", ", not an integer that fits"}},
      {"a power of 2^40", [&](json& j) { j[first_factor]["power"] = std::int64_t{1} << 40; }, {"`power` is ", ", not an integer that fits"}},
      {"an order of -1e300", [&](json& j) {
         j[first_factor]["kind"] = "signal", j[first_factor]["name"] = "y", j[first_factor]["order"] = -1e300;
       }, {"`order` is ", ", not an integer that fits"}},
      {"a version of 1e83", [](json& j) { j["version"] = 1e83; }, {"`version` is ", ", not an integer that fits"}},
      {"a span past the end of the source text", [](json& j) { j["equations"][0]["span"] = {{"offset", 5}, {"length", 1u << 30}}; },
       {"a span outside the source text"}},
      {"a negative span offset", [](json& j) { j["equations"][0]["span"] = {{"offset", -3}, {"length", 1}}; }, {"`offset` is ", ", not an integer that fits"}},
      // Found by the compiled-model fuzz target (an hour-long run): a function factor whose
      // `argument` key was misspelt reached the unit pass as a null pointer.
      {"a function without its argument", [&](json& j) { j[first_factor] = {{"kind", "function"}, {"name", "sin"}, {"asgument", nullptr}, {"power", 1}}; },
       {"a `function` factor without its argument"}},
      {"a power without its exponent", [&](json& j) {
         j[first_factor] = {{"kind", "power"}, {"argument", {{"text", "y"}, {"terms", json::array()}}}, {"power", 1}};
       }, {"a `power` factor without its exponent"}},
      {"an unknown function", [&](json& j) {
         j[first_factor] = {{"kind", "function"}, {"name", "sinh"}, {"argument", {{"text", "y"}, {"terms", json::array()}}}, {"power", 1}};
       }, {"an unknown function `sinh`"}},
      {"a derivative order past the compiler's 64", [&](json& j) {
         j[first_factor]["kind"] = "signal", j[first_factor]["name"] = "y", j[first_factor]["order"] = 65;
       }, {"derivative order of 65"}},
  };
  for (const auto& b : breakages) {
    json broken = good;
    b.apply(broken);
    error.clear();
    const auto read = compiled_model_from_json(broken, "m.sidc.json", error);
    EXPECT_FALSE(read.has_value()) << b.what;
    EXPECT_EQ(error.rfind("error: ", 0), 0u) << b.what << ": " << error;
    for (const char* part : b.expected) EXPECT_NE(error.find(part), std::string::npos) << b.what << ": `" << part << "` not in: " << error;
  }
}

// A compiled model nested 20 000 levels deep is refused from its text, in one pass, before the JSON
// library parses it (which copies members as it adds them: minutes at that depth).
TEST(CompiledModelFile, DeepJsonIsRefusedBeforeParsing) {
  const fs::path path = fs::temp_directory_path() / "sidc_deep_test.sidc.json";
  {
    std::ofstream out(path);
    out << R"({"format": "sidc-compiled-model", "version": 2, "equations": [)";
    for (int k = 0; k < 20000; ++k) out << R"({"terms": [{"factors": [{"kind": "integral", "argument": )";
    out << "{}";
    for (int k = 0; k < 20000; ++k) out << "}]}]}";
    out << "]}";
  }
  std::string error, warnings;
  EXPECT_FALSE(load_compiled_model(path.string(), error, warnings).has_value());
  EXPECT_NE(error.find("nested more than 2000 levels deep"), std::string::npos) << error;
  fs::remove(path);
}

// Values the reader takes today without a word and then misreads (a relation `=<` is read as
// `>=`, a power 0 drops the factor, an unknown setting value reaches evaluation_settings, which
// dereferences an empty optional or throws from std::stoi in `sidc fit`). Disabled until
// compiled_model_from_json checks them; enable it then (reported to the lead).
TEST(CompiledModelFile, ReaderRefusesValuesItWouldMisread) {
  json good = van_der_pol();
  // A guard, so that a relation can be broken.
  good["equations"][0]["known"]["terms"][0]["factors"].push_back(json::parse(R"({"kind": "guard", "conditions": [{
      "lhs": {"text": "y", "terms": [{"coefficient": {"num": 1, "den": 1}, "factors": [{"kind": "signal", "name": "y", "order": 0, "power": 1}], "span": null}]},
      "relation": "<=", "rhs": {"text": "0", "terms": []}}], "power": 1})"));
  std::string error;
  ASSERT_TRUE(compiled_model_from_json(good, "m.sidc.json", error).has_value()) << error;
  const json::json_pointer factor("/equations/0/known/terms/0/factors/0");
  const json::json_pointer guard("/equations/0/known/terms/0/factors/1");

  const std::vector<std::pair<const char*, std::function<void(json&)>>> breakages{
      {"unknown relation", [&](json& j) { j[guard]["conditions"][0]["relation"] = "=<"; }},
      {"unknown signal kind", [](json& j) { j["signals"][0]["kind"] = "outptu"; }},
      {"unknown parameter origin", [](json& j) { j["parameters"][0]["origin"] = "declard"; }},
      {"unknown constants mode", [](json& j) { j["equations"][0]["constants"] = "initail"; }},
      {"power 0", [&](json& j) { j[factor]["power"] = 0; }},
      {"a factor of a parameter not marked nonlinear", [&](json& j) { j[factor] = {{"kind", "parameter"}, {"name", "a1"}, {"power", 1}}; }},
      {"a nonlinear parameter without a guess", [](json& j) { j["parameters"][0]["nonlinear"] = true; }},
      {"a nonlinear parameter multiplying an operation", [](json& j) {
         j["parameters"][0]["nonlinear"] = true;
         j["parameters"][0]["guess"] = {{"num", 1}, {"den", 1}};
       }},
      {"a factor of an undeclared signal", [&](json& j) { j[factor]["name"] = "w"; }},
      {"unknown setting", [](json& j) { j["settings"]["as_written"]["derivativ"] = "savgol(7, 3)"; }},
      {"invalid setting value", [](json& j) { j["settings"]["as_written"]["every"] = "many"; }},
      {"invalid moving arc", [](json& j) { j["settings"]["as_written"]["derivative"] = "bogus"; }},
      {"text that does not match its hash", [](json& j) { j["source"]["text"] = "output y\n"; }},
  };
  for (const auto& [what, apply] : breakages) {
    json broken = good;
    apply(broken);
    error.clear();
    EXPECT_FALSE(compiled_model_from_json(broken, "m.sidc.json", error).has_value()) << what;
  }
}

}  // namespace
}  // namespace sidc
