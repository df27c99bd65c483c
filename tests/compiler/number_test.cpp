#include <gtest/gtest.h>

#include "ir/number.hpp"

using sidc::Number;

TEST(Number, DecimalsReadExactly) {
  const auto n = Number::parse("0.005");
  ASSERT_TRUE(n);
  EXPECT_TRUE(n->exact());
  EXPECT_EQ(n->numerator(), 1);
  EXPECT_EQ(n->denominator(), 200);
  EXPECT_EQ(Number::parse(".5")->denominator(), 2);
  EXPECT_EQ(Number::parse("5.")->numerator(), 5);
  EXPECT_EQ(Number::parse("2.5E+4")->numerator(), 25000);
  EXPECT_EQ(Number::parse("1e-3")->denominator(), 1000);
  EXPECT_FALSE(Number::parse("abc"));
  EXPECT_FALSE(Number::parse("1..6"));
}

TEST(Number, HugeLiteralsBecomeDoubles) {
  const auto n = Number::parse("1e300");
  ASSERT_TRUE(n);
  EXPECT_FALSE(n->exact());
  EXPECT_DOUBLE_EQ(n->value(), 1e300);
  const auto many_digits = Number::parse("3.14159265358979323846264338327950288");
  ASSERT_TRUE(many_digits);
  EXPECT_FALSE(many_digits->exact());
}

TEST(Number, ArithmeticIsExactAndFallsBackOnOverflow) {
  const Number third = Number(1) / Number(3);
  EXPECT_EQ(third + third + third, Number(1));
  EXPECT_EQ((third * Number(3)).to_string(), "1");
  const Number big = Number(INT64_MAX / 2);
  const Number product = big * big;
  EXPECT_FALSE(product.exact());
  EXPECT_NEAR(product.value() / (big.value() * big.value()), 1.0, 1e-15);
}

TEST(Number, PrintsDecimalsRationalsAndDoubles) {
  EXPECT_EQ(Number::parse("0.005")->to_string(), "0.005");
  EXPECT_EQ((-*Number::parse("0.0025")).to_string(), "-0.0025");
  EXPECT_EQ((Number(1) / Number(3)).to_string(), "1/3");
  EXPECT_EQ((Number(-7) / Number(6)).to_string(), "-7/6");
  EXPECT_EQ(Number::real(0.1).to_string(), "0.1");
  EXPECT_EQ(Number(1).pow(-1).to_string(), "1");
  EXPECT_EQ(Number(2).pow(-3).to_string(), "1/8");
  EXPECT_EQ(Number::rational(3, 8).to_string(), "0.375");
  EXPECT_EQ(Number::rational(1, 20).to_string(), "0.05");
}

TEST(Number, ComparesAcrossForms) {
  EXPECT_EQ(compare(Number::rational(1, 2), Number::real(0.5)), 0);
  EXPECT_LT(Number::rational(1, 3), Number::rational(1, 2));
  EXPECT_LT(Number(-1), Number(0));
}
