// Parameters that enter nonlinearly (`param L = 1.2`, issue 15 item 2): which parameters lower_pass
// marks nonlinear, that normalization leaves them in the operations, that a guess is a number
// (constants folded, a family sharing it), and that ir/fix_parameters.hpp holds them at values and
// renumbers the rest without touching anything else.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "compile_text.hpp"
#include "compiler/explicit_form_pass.hpp"
#include "ir/fix_parameters.hpp"
#include "ir/print.hpp"

namespace sidc {
namespace {

ir::Model ok(const CompileResult& r) {
  EXPECT_TRUE(r.ok()) << r.diagnostics.render_all();
  return r.normalized ? *r.normalized : ir::Model{};
}

TEST(NonlinearParameters, OnlyGuessedParametersInNonlinearPlacesAreMarked) {
  const auto r = testing::compile_text(
      "input x\noutput y\nconst L0 = 0.6\nparam m, c[1..2] = 0.5, b, L = 2*L0, k = 0.1, p = 1.5\n"
      "m*y'' + c[1]*y' + c[2]*y + b*exp(-k*t)*sin(L*y) + y^p = x\n");
  const ir::Model m = ok(r);
  std::vector<std::string> nonlinear;
  for (const auto& p : m.parameters)
    if (p.nonlinear) nonlinear.push_back(p.name);
  EXPECT_EQ(nonlinear, (std::vector<std::string>{"L", "k", "p"}));
  // Guessed but linear: fitted linearly, the guess kept for the record.
  ASSERT_TRUE(m.parameters[1].guess && m.parameters[2].guess);
  EXPECT_EQ(m.parameters[1].guess->to_string(), "1/2");
  EXPECT_EQ(m.parameters[2].guess->to_string(), "1/2");
  EXPECT_DOUBLE_EQ(m.parameters[4].guess->value(), 1.2);
  // The linear parameters are split off; the nonlinear ones stay inside their operations.
  const ir::Equation& e = m.equations[0];
  std::vector<std::string> columns;
  for (const auto& t : e.terms) columns.push_back(m.parameters[static_cast<std::size_t>(t.parameter)].name + ": " + print(t.operation));
  EXPECT_EQ(columns, (std::vector<std::string>{"m: y''", "c[1]: y'", "c[2]: y", "b: exp(-k*t)*sin(L*y)"}));
  EXPECT_EQ(print(e.known), "x - exp(p*log(y))");
}

TEST(NonlinearParameters, ABesideParameterWithAGuessIsNonlinear) {
  const ir::Model m = ok(testing::compile_text("input x\noutput y\nparam a, L = 2\na*L*y' + y = x\n"));
  EXPECT_FALSE(m.parameters[0].nonlinear);
  EXPECT_TRUE(m.parameters[1].nonlinear);
  ASSERT_EQ(m.equations[0].terms.size(), 1u);
  EXPECT_EQ(print(m.equations[0].terms[0].operation), "L*y'");
}

TEST(NonlinearParameters, ErrorsNameTheParameterAndWhatToWrite) {
  const auto no_guess = testing::compile_text("input x\noutput y\nparam a, k\na*y' + exp(-k*t)*y = x\n");
  ASSERT_FALSE(no_guess.ok());
  EXPECT_NE(no_guess.diagnostics.render_all().find("give `k` an initial guess (`param k = 1.5`)"), std::string::npos)
      << no_guess.diagnostics.render_all();
  // A threshold: with a guess it stands in a guard or sign() (nonlinear); without one it is an error.
  const auto guard = testing::compile_text("input x\noutput y\nparam a, y0 = 0.1, v = 1\na*y' + [y > y0]*y + sign(v*y') = x\n");
  ASSERT_TRUE(guard.ok()) << guard.diagnostics.render_all();
  EXPECT_TRUE(guard.normalized->parameters[1].nonlinear && guard.normalized->parameters[2].nonlinear);
  const auto unguessed = testing::compile_text("input x\noutput y\nparam a, b, y0\na*y' + b*[y > y0]*y = x\n");
  ASSERT_FALSE(unguessed.ok());
  EXPECT_EQ(unguessed.diagnostics.items.front().code, "nonlinear-parameter");
  EXPECT_NE(unguessed.diagnostics.render_all().find("inside a guard"), std::string::npos);
  const auto signal = testing::compile_text("input x\noutput y\nparam a, L = y\na*y' + sin(L*y) = x\n");
  ASSERT_FALSE(signal.ok());
  EXPECT_NE(signal.diagnostics.render_all().find("a parameter's initial guess must be a number"), std::string::npos);
}

// A plot may use a nonlinear parameter the equations hold at a value, not one only the plot uses.
TEST(NonlinearParameters, PlotsUseOnlyParametersTheEquationsFit) {
  const std::string model = "input x\noutput y\nparam m, c, k, L = 1.2\nm*y'' + c*y' + k*sin(L*y) = x\n";
  const auto fitted = testing::compile_text(model + "plot spring(y) = k*sin(L*y)\n");
  ASSERT_TRUE(fitted.ok()) << fitted.diagnostics.render_all();
  ASSERT_EQ(fitted.normalized->plots.size(), 1u);
  EXPECT_EQ(print(fitted.normalized->plots[0].terms[0].operation), "sin(L*y)");
  const auto unfitted = testing::compile_text("input x\noutput y\nparam m, c, k, P = 2\nm*y'' + c*y' + k*y = x\nplot spring(y) = k*sin(P*y)\n");
  ASSERT_FALSE(unfitted.ok());
  EXPECT_NE(unfitted.diagnostics.render_all().find("`P`"), std::string::npos) << unfitted.diagnostics.render_all();
}

TEST(NonlinearParameters, PrintedModelCarriesTheGuesses) {
  const auto r = testing::compile_text("input x\noutput y\nparam m, c[1..2] = 0.5, L = 1.2\nm*y'' + c[1]*y' + c[2]*sin(L*y) = x\n");
  const ir::Model m = ok(r);
  const std::string text = print(m);
  EXPECT_NE(text.find("param m, c[1..2] = 1/2, L = 1.2\n"), std::string::npos) << text;
  // The printed model compiles to the same model.
  const auto again = testing::compile_text(text);
  EXPECT_EQ(print(ok(again)), text);
}

TEST(NonlinearParameters, FixedModelHoldsThemAtValuesAndRenumbersTheRest) {
  const auto r = testing::compile_text("input x\noutput y\nparam a, L = 1.2, b\na*y'' + b*sin(L*y) + y' = x\n");
  const ir::Model m = ok(r);
  ASSERT_TRUE(has_nonlinear_parameters(m));
  const std::vector<double> guesses = nonlinear_guesses(m);
  EXPECT_TRUE(std::isnan(guesses[0]) && std::isnan(guesses[2]));
  EXPECT_DOUBLE_EQ(guesses[1], 1.2);
  // A value given for a linear parameter is not substituted.
  const ir::Model fixed = fix_nonlinear(m, {9.0, 0.5, 9.0});
  ASSERT_EQ(fixed.parameters.size(), 2u);
  EXPECT_EQ(fixed.parameters[0].name, "a");
  EXPECT_EQ(fixed.parameters[1].name, "b");
  EXPECT_FALSE(has_nonlinear_parameters(fixed));
  ASSERT_EQ(fixed.equations[0].terms.size(), 2u);
  EXPECT_EQ(fixed.equations[0].terms[1].parameter, 1);
  EXPECT_EQ(print(fixed.equations[0].terms[1].operation), "sin(0.5*y)");
  EXPECT_EQ(linear_part(m, {1.0, 0.5, 3.0}), (std::vector<double>{1.0, 3.0}));
  // The explicit form: held and renumbered alike, or held with every index kept.
  const auto form = explicit_form(m);
  ASSERT_TRUE(std::holds_alternative<ExplicitForm>(form));
  const ExplicitForm held = fix_nonlinear(std::get<ExplicitForm>(form), m, {0.0, 0.5, 0.0});
  const ExplicitForm kept = substitute_nonlinear(std::get<ExplicitForm>(form), m, {0.0, 0.5, 0.0});
  ASSERT_EQ(held.rest[0].terms.size(), 1u);
  EXPECT_EQ(held.rest[0].terms[0].parameter, 1);
  EXPECT_EQ(kept.rest[0].terms[0].parameter, 2);
  EXPECT_EQ(print(held.rest[0].terms[0].operation), "sin(0.5*y)");
  // A model without nonlinear parameters comes back as it was.
  const ir::Model plain = ok(testing::compile_text("input x\noutput y\nparam a, b\na*y' + b*y = x\n"));
  EXPECT_EQ(print(fix_nonlinear(plain, {1.0, 2.0})), print(plain));
}

}  // namespace
}  // namespace sidc
