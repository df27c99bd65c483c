// Structural tests of integrate_pass: each exact rule, and what must stay a numerical integral.
#include <gtest/gtest.h>

#include "compile_text.hpp"
#include "ir/differentiate.hpp"
#include "compiler/integrate_pass.hpp"
#include "ir/print.hpp"

namespace sidc {
namespace {

// The right-hand side `known` after integrating `expression = 0`'s parameter-free terms once.
std::string integrated_known(const std::string& expression, bool initial = false) {
  const auto r = testing::compile_text("input x\noutput y\nparam a\na*y = " + expression + "\n", {{}, "normalize"});
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  if (!r.ok()) return "<error>";
  return print(antiderivative(r.normalized->equations[0].known, initial));
}

TEST(Antiderivative, ExactRules) {
  EXPECT_EQ(integrated_known("y''"), "y'");                      // int(der(f, k)) = der(f, k-1)
  EXPECT_EQ(integrated_known("y^2*y'"), "y^3/3");                // eq. 2-2.7
  EXPECT_EQ(integrated_known("y'*y''"), "y'^2/2");               // products of a signal's derivatives
  EXPECT_EQ(integrated_known("x'*y + x*y'"), "x*y");             // the product rule
  EXPECT_EQ(integrated_known("3"), "3*tau");                     // constants
  EXPECT_EQ(integrated_known("t"), "t^2/2");
  EXPECT_EQ(integrated_known("5*y^4*y' + y"), "y^5 + int(y)");
}

TEST(Antiderivative, NoExactAntiderivativeMeansNumericalIntegral) {
  EXPECT_EQ(integrated_known("y''*y"), "int(y''*y)");
  EXPECT_EQ(integrated_known("sin(y)*y''"), "int(y''*sin(y))");
  EXPECT_EQ(integrated_known("[y' > 0]*y''"), "int(y''*[y' > 0])");
  EXPECT_EQ(integrated_known("x'*y + 2*x*y'"), "int(x'*y) + 2*int(x*y')");  // not an exact derivative
}

TEST(Antiderivative, InitialValuesSubtracted) {
  EXPECT_EQ(integrated_known("y'", true), "y - y(t0)");
  EXPECT_EQ(integrated_known("x'*y + x*y'", true), "x*y - x(t0)*y(t0)");
  EXPECT_EQ(integrated_known("2", true), "2*tau");
  EXPECT_EQ(integrated_known("t", true), "t^2/2 - t0^2/2");
}

TEST(Antiderivative, NoValueAtT0InsideAFunctionMeansNumericalIntegral) {
  // int(der(u, 1)) = u, but with `constants = initial` u(t0) must be written out, and a guard
  // inside sin() has no value at t0: the term stays a numerical integral (it once was an internal error).
  EXPECT_EQ(integrated_known("der(sin([y > 0]*y), 1)", true), "int(der(sin(y*[y > 0]), 1))");
  EXPECT_EQ(integrated_known("der(sin([y > 0]*y), 1)", false), "sin(y*[y > 0])");
}

TEST(Antiderivative, EveryExactPieceDifferentiatesBack) {
  // Property: for sums whose terms have exact antiderivatives, d/dt of the result gives them back.
  for (const char* e : {"y''", "y^2*y'", "y'*y''", "x'*y + x*y'", "7*y^6*y' + y'''", "t*y' + y"}) {
    const auto r = testing::compile_text(std::string("input x\noutput y\nparam a\na*y = ") + e + "\n", {{}, "normalize"});
    ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
    const ir::Sum& known = r.normalized->equations[0].known;
    const auto back = differentiate(antiderivative(known, false));
    ASSERT_TRUE(back) << e;
    EXPECT_EQ(print(*back), print(known)) << e;
  }
}

TEST(IntegratePass, AutoChoosesTheSmallestUsefulCount) {
  const auto vdp = testing::compile_text("output y\nparam a1, a2, a3\nset integrate = auto\ny'' + a1*y' + a2*y'*y^2 + a3*y = 0\n");
  ASSERT_TRUE(vdp.ok()) << vdp.diagnostics.render_all();
  EXPECT_EQ(vdp.integrated->equations[0].integrations, 2);
  const auto guarded = testing::compile_text("input x\noutput y\nparam m, c\nset integrate = auto\nm*y'' + c*y'^3*[y' > 0] = x\n");
  ASSERT_TRUE(guarded.ok()) << guarded.diagnostics.render_all();
  EXPECT_EQ(guarded.integrated->equations[0].integrations, 1);  // a second pass leaves y' inside int()
}

TEST(IntegratePass, ConstantsMultiplyTimePolynomials) {
  const auto r = testing::compile_text("input x\noutput y\nparam a[1..4]\nset integrate = 3\na[1]*y''' + a[2]*y'' + a[3]*y' + a[4]*y = x\n");
  ASSERT_TRUE(r.ok()) << r.diagnostics.render_all();
  EXPECT_EQ(print(r.integrated->equations[0], *r.integrated),
            "a[1]*y + a[2]*int(y) + a[3]*int(int(y)) + a[4]*int(int(int(y))) + C1*tau^2/2 + C2*tau + C3 = int(int(int(x)))");
}

}  // namespace
}  // namespace sidc
