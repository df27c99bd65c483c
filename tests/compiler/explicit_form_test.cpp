// compiler/explicit_form_pass: equations solved for each output's highest derivative, structurally.
// (The numerical check, that the explicit form agrees with the equation it came from, is in
// tests/runtime/simulate_test.cpp, where the point evaluator lives.)
#include "compiler/explicit_form_pass.hpp"

#include <gtest/gtest.h>

#include "compile_text.hpp"
#include "ir/print.hpp"

namespace sidc {
namespace {

ir::Model normalized(const std::string& text) {
  CompileResult r = testing::compile_text(text);
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return *r.normalized;
}

Diagnostic failure(const std::string& text) {
  auto form = explicit_form(normalized(text));
  EXPECT_TRUE(std::holds_alternative<Diagnostic>(form)) << "expected a diagnostic for:\n" << text;
  return std::holds_alternative<Diagnostic>(form) ? std::get<Diagnostic>(form) : Diagnostic{};
}

TEST(ExplicitForm, SecondOrderSplitsCoefficientAndRest) {
  const ir::Model m = normalized("input x\noutput y\nparam m, c, k\nm*y'' + c*y'*[y' <= 0] + k*y^2 = x\n");
  auto form = explicit_form(m);
  ASSERT_TRUE(std::holds_alternative<ExplicitForm>(form)) << render(std::get<Diagnostic>(form));
  const auto& f = std::get<ExplicitForm>(form);
  ASSERT_EQ(f.outputs.size(), 1u);
  EXPECT_EQ(f.outputs[0].name, "y");
  EXPECT_EQ(f.outputs[0].order, 2);
  EXPECT_EQ(f.state_size(), 2u);
  // Coefficient of y'': m * 1, nothing else.
  const ParametricSum& a = f.coefficient[0][0];
  ASSERT_EQ(a.terms.size(), 1u);
  EXPECT_EQ(m.parameters[static_cast<std::size_t>(a.terms[0].parameter)].name, "m");
  EXPECT_EQ(print(a.terms[0].operation), "1");
  EXPECT_TRUE(a.constant.empty());
  // Rest: c*y'*[y' <= 0] + k*y^2 - x.
  const ParametricSum& r = f.rest[0];
  ASSERT_EQ(r.terms.size(), 2u);
  EXPECT_EQ(print(r.constant), "-x");
  ASSERT_EQ(f.switching_functions.size(), 1u);
  EXPECT_EQ(print(f.switching_functions[0]), "y'");
}

TEST(ExplicitForm, CoefficientMayDependOnLowerDerivativesAndParameterFreeTerms) {
  // y'' without a parameter goes to the known side in normalization; it must come back as the
  // parameter-free part of the coefficient, with the sign of the left side.
  const ir::Model m = normalized("input x\noutput y\nparam a, b\ny'' + a*y*y'' + b*y' = x\n");
  auto form = explicit_form(m);
  ASSERT_TRUE(std::holds_alternative<ExplicitForm>(form)) << render(std::get<Diagnostic>(form));
  const auto& f = std::get<ExplicitForm>(form);
  const ParametricSum& a = f.coefficient[0][0];
  EXPECT_EQ(print(a.constant), "1");
  ASSERT_EQ(a.terms.size(), 1u);
  EXPECT_EQ(print(a.terms[0].operation), "y");
}

TEST(ExplicitForm, MultiOutputMatching) {
  // Equation 1 holds z's highest derivative, equation 2 y's: the matching finds it.
  const ir::Model m = normalized("input u\noutput y, z\nparam a, b, c, d\na*z' + b*y = u\nc*y'' + d*z = u\n");
  auto form = explicit_form(m);
  ASSERT_TRUE(std::holds_alternative<ExplicitForm>(form)) << render(std::get<Diagnostic>(form));
  const auto& f = std::get<ExplicitForm>(form);
  ASSERT_EQ(f.outputs.size(), 2u);
  EXPECT_EQ(f.outputs[0].order, 2);
  EXPECT_EQ(f.outputs[1].order, 1);
  EXPECT_EQ(f.matched[0], 1);  // equation 1 -> z
  EXPECT_EQ(f.matched[1], 0);  // equation 2 -> y
  EXPECT_EQ(f.state_size(), 3u);
}

TEST(ExplicitForm, NonlinearHighestDerivativeIsRefused) {
  EXPECT_EQ(failure("input x\noutput y\nparam a, b\na*y''^2 + b*y = x\n").code, "highest-derivative-nonlinear");
  EXPECT_EQ(failure("input x\noutput y\nparam a, b\na*sin(y'') + b*y = x\n").code, "highest-derivative-nonlinear");
  EXPECT_EQ(failure("input x\noutput y\nparam a, b, c\na*y'' + b*y'*[y'' > 0] + c*y = x\n").code, "highest-derivative-nonlinear");
  const Diagnostic d = failure("input x\noutput y, z\nparam a, b, c, d\na*y''*z' + b*y = x\nc*z' + d*y = x\n");
  EXPECT_EQ(d.code, "highest-derivative-nonlinear");
  EXPECT_NE(d.message.find("another highest derivative"), std::string::npos) << d.message;
  EXPECT_GT(d.span.length(), 0u);  // points at the term
}

TEST(ExplicitForm, IntegralsStaticModelsAndCountsAreRefused) {
  EXPECT_EQ(failure("input x\noutput y\nparam a, b\nset integrate = 0\na*y' + b*int(y) = x\n").code, "simulate-integral");
  EXPECT_EQ(failure("input x\noutput y\nparam a, b\na*y + b*y^2 = x\n").code, "simulate-static-output");
  EXPECT_EQ(failure("input x\noutput y\nparam a, b, c, d\na*y' + b*y = x\nc*y' + d*y = x^2\n").code, "simulate-equation-count");
  // Both equations contain only y's highest derivative: no equation for z'.
  EXPECT_EQ(failure("input u\noutput y, z\nparam a, b, c, d\na*y' + b*z = u\nc*y' + d*z = u^2\n").code, "simulate-static-output");
  EXPECT_EQ(failure("input u\noutput y, z\nparam a, b, c, d\na*y' + b*z' = u\nc*y' + d*z = u^2\nc*z' + a*y = u\n").code,
            "simulate-equation-count");
}

TEST(ExplicitForm, UnmatchableHighestDerivatives) {
  // The second equation has no highest derivative at all: an algebraic constraint.
  const Diagnostic d = failure("input u\noutput y, z\nparam a, b, c, d\na*y' + b*z' = u\nc*y + d*z = u\n");
  EXPECT_EQ(d.code, "highest-derivatives-unmatched");
  EXPECT_NE(d.message.find("`y'`, `z'`"), std::string::npos) << d.message;
}

}  // namespace
}  // namespace sidc
