// Units: reading and printing them (ir/units.hpp), and the parameters' units derived by
// compiler/unit_pass.cpp, through a compile and back through the compiled-model file.
#include <gtest/gtest.h>

#include "compile_text.hpp"
#include "ir/compiled_model.hpp"
#include "ir/units.hpp"

namespace sidc {
namespace {

ir::Unit unit(const char* text) {
  auto u = ir::parse_unit(text);
  EXPECT_TRUE(u) << text;
  return u ? *u : ir::Unit{};
}

std::map<std::string, std::string> parameter_units(const ir::Model& m) {
  std::map<std::string, std::string> out;
  for (const auto& p : m.parameters) out[p.name] = p.unit ? to_string(*p.unit) : "-";
  return out;
}

std::vector<std::string> error_codes(const CompileResult& r) {
  std::vector<std::string> codes;
  for (const auto& d : r.diagnostics.items) codes.push_back(d.code);
  return codes;
}

TEST(Units, ReadAndPrintCanonically) {
  EXPECT_EQ(to_string(unit("kg*m^2/s^2")), "kg*m^2/s^2");
  EXPECT_EQ(to_string(unit("s^-2 * m^2 * kg")), "kg*m^2/s^2");
  EXPECT_EQ(to_string(unit("m/(s*K)")), "m/(s*K)");
  EXPECT_EQ(to_string(unit("m*N")), "N*m");
  EXPECT_EQ(to_string(unit("1/s")), "1/s");
  EXPECT_EQ(to_string(unit("1")), "1");
  EXPECT_EQ(to_string(unit("m^(1/2)")), "m^(1/2)");
  EXPECT_EQ(to_string(unit("m/m")), "1");
  EXPECT_EQ(to_string(unit("%")), "%");
}

TEST(Units, ErrorsSayWhereAndWhat) {
  ir::UnitParseError e;
  EXPECT_FALSE(ir::parse_unit("m^", &e));
  EXPECT_EQ(e.offset, 2u);
  EXPECT_FALSE(ir::parse_unit("1..3", &e));
  EXPECT_EQ(e.offset, 1u);
  EXPECT_FALSE(ir::parse_unit("", &e));
  EXPECT_FALSE(ir::parse_unit("m*", &e));
  EXPECT_FALSE(ir::parse_unit("(m", &e));
  EXPECT_FALSE(ir::parse_unit("m^(1/0)", &e));
  EXPECT_FALSE(ir::parse_unit("m^1000", &e));
}

TEST(Units, DerivedSiUnitsAgreeWithTheirBaseForm) {
  EXPECT_TRUE(ir::same_dimension(unit("N*m"), unit("J")));
  EXPECT_TRUE(ir::same_dimension(unit("N*m"), unit("kg*m^2/s^2")));
  EXPECT_TRUE(ir::same_dimension(unit("V*A"), unit("W")));
  EXPECT_TRUE(ir::same_dimension(unit("rad/s"), unit("Hz")));
  EXPECT_TRUE(ir::is_dimensionless(unit("rad")));
  EXPECT_FALSE(ir::same_dimension(unit("mm"), unit("m")));  // symbols, not scales
  EXPECT_FALSE(ir::same_dimension(unit("N"), unit("N*m")));
}

TEST(Units, TheShorterOfTheTwoFormsIsPrinted) {
  EXPECT_EQ(to_string(ir::simplest(unit("N*s^2/m"))), "kg");
  EXPECT_EQ(to_string(ir::simplest(unit("V/mm"))), "V/mm");
  EXPECT_EQ(to_string(ir::simplest(unit("N*m*s^2/rad"))), "kg*m^2/rad");
}

TEST(Units, EachParameterFromItsTermAndTheKnownSide) {
  auto r = testing::compile_text(
      "input F [N]\noutput y [m]\nparam m, c, k, k3\nset form = derivative\nm*y'' + c*y' + k*y + k3*y^3 = F\n");
  ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
  EXPECT_EQ(parameter_units(*r.integrated),
            (std::map<std::string, std::string>{{"m", "kg"}, {"c", "kg/s"}, {"k", "N/m"}, {"k3", "N/m^3"}}));
}

TEST(Units, FunctionsGuardsAndSignOfAPendulum) {
  auto r = testing::compile_text(
      "input u [N*m]\noutput theta [rad]\nparam J, c, f, mgl\nset form = derivative\n"
      "J*theta'' + c*theta' + f*sign(theta') + mgl*sin(theta) = u\n");
  ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
  EXPECT_EQ(parameter_units(*r.integrated), (std::map<std::string, std::string>{
                                                {"J", "kg*m^2/rad"}, {"c", "N*m*s/rad"}, {"f", "N*m"}, {"mgl", "N*m"}}));
}

TEST(Units, IntegrationConstantsAndTheTimeUnit) {
  auto r = testing::compile_text(
      "input x [kg/min]\noutput y [kg]\nparam a, b\nset time_unit = min\nset integrate = 1\na*y' + b*y = x\n");
  ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
  EXPECT_EQ(parameter_units(*r.integrated), (std::map<std::string, std::string>{{"a", "1"}, {"b", "1/min"}, {"C1", "kg"}}));
}

TEST(Units, ASignalWithoutUnitLeavesItsParametersWithout) {
  auto r = testing::compile_text("input x [N], z\noutput y [m]\nparam a, b\nset form = derivative\na*y' + b*z = x\n");
  ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
  EXPECT_EQ(parameter_units(*r.integrated), (std::map<std::string, std::string>{{"a", "kg/s"}, {"b", "-"}}));
}

TEST(Units, ModelsWithoutUnitsAreLeftAlone) {
  auto r = testing::compile_text("input x\noutput y\nparam a, b\na*y' + b*sin(y) = x\n");
  ASSERT_TRUE(r.ok());
  for (const auto& p : r.integrated->parameters) EXPECT_FALSE(p.unit) << p.name;
}

TEST(Units, WhatCannotMatchIsAnErrorAtTheTerm) {
  EXPECT_EQ(error_codes(testing::compile_text("input x [N], z [m]\noutput y [m]\nparam a\na*y' = x + z\n")),
            std::vector<std::string>{"unit-mismatch"});
  EXPECT_EQ(error_codes(testing::compile_text("input x [N]\noutput y [m]\nparam a, b\na*sin(y) + b*y = x\n")),
            std::vector<std::string>{"function-of-unit"});
  EXPECT_EQ(error_codes(testing::compile_text("input x [N]\noutput y [m]\nparam a\na*(y + y') = x\n")),
            std::vector<std::string>{"operation-unit-mismatch"});
  EXPECT_EQ(error_codes(testing::compile_text("input x [N], z [m]\noutput y [m]\nparam a, b\na*y' + b*y = x\na*y = z\n")),
            std::vector<std::string>{"parameter-unit-conflict"});
  EXPECT_EQ(error_codes(testing::compile_text("input x [N]\noutput y [m^]\nparam a\na*y = x\n")),
            std::vector<std::string>{"bad-unit"});
  // A number factor carries the unit of a function's argument: sin(2*pi*t) is fine.
  EXPECT_TRUE(testing::compile_text("input x [N]\noutput y [m]\nparam a, b\na*y + b*sin(2*pi*t) = x\n").ok());
}

TEST(Units, TheCompiledModelKeepsThem) {
  auto r = testing::compile_text("input u [N*m]\noutput theta [rad]\nparam J, c\nset form = derivative\nJ*theta'' + c*theta' = u\n");
  ASSERT_TRUE(r.ok());
  const auto j = to_json(compiled_model(r.parsed.source, *r.normalized, *r.integrated));
  EXPECT_EQ(j["signals"][1]["unit"], "rad");
  EXPECT_EQ(j["parameters"][0]["unit"], "kg*m^2/rad");
  std::string error;
  const auto back = read_compiled_model(nlohmann::ordered_json::parse(j.dump()), "test.sidc.json", error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(parameter_units(back->integrated), parameter_units(*r.integrated));
  EXPECT_EQ(parameter_units(back->normalized), parameter_units(*r.normalized));
}

}  // namespace
}  // namespace sidc
