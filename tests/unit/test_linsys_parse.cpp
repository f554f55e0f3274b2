// The plant text parser: the report's expressions, and errors that point at the character.
#include "common/error.hpp"
#include "linsys/parse.hpp"
#include "test_support_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace mcg::linsys {
namespace {

std::string error_of(const char* text) {
  return test::error_of([&] { parse_tf(text, "--plant"); });
}

TEST(LinsysParse, ReportPlantsEvaluateAsWritten) {
  const Complex s(3.0, 40.0);
  const ParsedTf g = parse_tf("16.557/((s/65+1)*(s/950+1))", "t");
  ASSERT_EQ(g.domain, Domain::s);
  const Complex want = 16.557 / ((s / 65.0 + 1.0) * (s / 950.0 + 1.0));
  EXPECT_NEAR(std::abs(g.tf.eval(s) - want), 0.0, 1e-14);
  const ParsedTf pi = parse_tf("4658*(s/500+1)/s", "t");
  EXPECT_NEAR(std::abs(pi.tf.eval(s) - 4658.0 * (s / 500.0 + 1.0) / s), 0.0, 1e-10);
  const ParsedTf den = parse_tf("1/(1.6194e-5*s^2 + .016437*s + 1)", "t");
  EXPECT_EQ(trim(den.tf.den), (Poly{1.6194e-5, 0.016437, 1.0}));
}

TEST(LinsysParse, DelaysAndZ) {
  const ParsedTf d = parse_tf("0.5*exp(-0.002*s)/(s+1)", "t");
  EXPECT_DOUBLE_EQ(d.tf.delay_s, 0.002);
  EXPECT_NEAR(d.tf.dc_gain(), 0.5, 1e-15);
  const ParsedTf z = parse_tf("z^-1", "t");
  ASSERT_EQ(z.domain, Domain::z);
  EXPECT_EQ(trim(z.tf.num), (Poly{1.0}));
  EXPECT_EQ(trim(z.tf.den), (Poly{1.0, 0.0}));
  // (11.645 − 6.987 z^−1)/(1 − z^−1): the common z cancels.
  const ParsedTf pi = parse_tf("(11.645 - 6.987*z^-1)/(1 - z^-1)", "t");
  EXPECT_EQ(trim(pi.tf.num), (Poly{11.645, -6.987}));
  EXPECT_EQ(trim(pi.tf.den), (Poly{1.0, -1.0}));
  EXPECT_FALSE(parse_tf("42", "t").domain.has_value());
}

TEST(LinsysParse, SizesAreBoundedNotWrapped) {
  // An overflowing exponent once read as 0, and nested powers grew to degree 64^3.
  EXPECT_EQ(error_of("1/(s+1)^99999999999"), "--plant: exponent too large (at most 64) at character 9");
  EXPECT_EQ(error_of("1/(s+1)^65"), "--plant: exponent too large (at most 64) at character 9");
  EXPECT_EQ(error_of("1/(((s+1)^64)^64)^64"), "--plant: degree 4096 above the limit of 256 at character 14");
  EXPECT_EQ(error_of("(s+1)^64*(s+1)^64*(s+1)^64*(s+1)^64*(s+1)"),
            "--plant: degree 257 above the limit of 256 at character 36");
  EXPECT_EQ(error_of("(s+1)^64*(s+1)^64*(s+1)^64*(s+1)^64+1/s"),
            "--plant: degree 257 above the limit of 256 at character 36");
  EXPECT_EQ(trim(parse_tf("(s+1)^64*(s+1)^64*(s+1)^64*(s+1)^64", "t").tf.num).size(), 257u);
  EXPECT_EQ(error_of("1e999/s"), "--plant: number out of range at character 1");
  EXPECT_EQ(error_of("1e300*s*1e300/(s+1)"), "--plant: number out of range at character 8");
  EXPECT_EQ(error_of("10^64^2"), "--plant: unexpected '^' at character 6");
  EXPECT_EQ(error_of("1e10^64"), "--plant: number out of range at character 5");
  EXPECT_EQ(error_of("exp(1000)"), "--plant: number out of range at character 1");
  EXPECT_EQ(error_of("exp(-1e308*s)*exp(-1e308*s)"), "--plant: number out of range at character 14");
}

TEST(LinsysParse, ErrorsPointAtTheCharacter) {
  EXPECT_EQ(error_of("16.557/((s/65+1)*(s/950+1)"), "--plant: unbalanced '(' at character 8");
  EXPECT_EQ(error_of("1/(s+1))"), "--plant: unexpected ')' at character 8");
  EXPECT_EQ(error_of("1/(s+z)"), "--plant: s and z mixed at character 6");
  EXPECT_EQ(error_of("2*x/(s+1)"), "--plant: unknown symbol 'x' at character 3");
  EXPECT_EQ(error_of("1/0"), "--plant: division by zero at character 2");
  EXPECT_EQ(error_of("s^1.5"), "--plant: expected a whole-number exponent at character 3");
  EXPECT_EQ(error_of("1/(s+)"), "--plant: unexpected ')' at character 6");
  EXPECT_EQ(error_of("2 3"), "--plant: unexpected '3' at character 3");
  EXPECT_EQ(error_of("s 2"), "--plant: unexpected '2' at character 3");
  EXPECT_EQ(error_of("s^2 3"), "--plant: unexpected '3' at character 5");
  EXPECT_EQ(error_of("(s+1)2"), "--plant: unexpected '2' at character 6");
  EXPECT_EQ(error_of(""), "--plant: empty expression at character 1");
  EXPECT_EQ(error_of("exp(-0.002*s)/(s+1) + 1"), "--plant: terms with different delays added at character 21");
  EXPECT_EQ(error_of("exp(s^2)"), "--plant: exp() takes c - tau*s (a delay) at character 1");
  EXPECT_EQ(error_of("exp(0.1*s)"), "--plant: negative delay 0.1 s (a prediction) is not causal");
}

TEST(LinsysParse, ImplicitMultiplicationWhereUnambiguous) {
  const Complex s(3.0, 40.0);
  const auto near = [&](const char* text, Complex want) {
    const ParsedTf g = parse_tf(text, "t");
    EXPECT_NEAR(std::abs(g.tf.eval(s) - want), 0.0, 1e-12 * std::abs(want)) << text;
  };
  near("16.557/((s/65+1)(s/950+1))", 16.557 / ((s / 65.0 + 1.0) * (s / 950.0 + 1.0)));
  near("2(s+1)", 2.0 * (s + 1.0));
  near("2s", 2.0 * s);
  near("2 s", 2.0 * s);
  near("-2s^2", -2.0 * s * s);
  near("s(s+1)(s+2)", s * (s + 1.0) * (s + 2.0));
  near("(s+1)s", (s + 1.0) * s);
  near("0.5exp(-0.01s)/(s+1)", 0.5 / (s + 1.0));
  near("1e-3s", 1e-3 * s);
  near("4658(s/500+1)/s", 4658.0 * (s / 500.0 + 1.0) / s);
  EXPECT_DOUBLE_EQ(parse_tf("0.5exp(-0.01s)/(s+1)", "t").tf.delay_s, 0.01);
  const ParsedTf z = parse_tf("(11.645 - 6.987z^-1)/(1 - z^-1)", "t");
  EXPECT_EQ(trim(z.tf.num), (Poly{11.645, -6.987}));
}

TEST(LinsysParse, JuxtapositionAfterDivisionIsRefused) {
  EXPECT_EQ(error_of("1/2s"),
            "--plant: implicit multiplication after '/' is ambiguous (write '*' or parentheses) at character 4");
  EXPECT_EQ(error_of("1/(s+1)(s+2)"),
            "--plant: implicit multiplication after '/' is ambiguous (write '*' or parentheses) at character 8");
  EXPECT_EQ(error_of("2x(s+1)"), "--plant: unknown symbol 'x' at character 2");
}

}  // namespace
}  // namespace mcg::linsys

namespace mcg::linsys {
namespace {

TEST(LinsysParse, DepthAndLengthAreBoundedWithoutRecursion) {
  // 7000 parentheses overflowed the stack (2000 under AddressSanitizer).
  const std::string deep = "1/" + std::string(7000, '(') + "s+1" + std::string(7000, ')');
  EXPECT_THROW((void)parse_tf(deep, "--plant"), mcg::Error);
  try {
    (void)parse_tf(deep, "--plant");
  } catch (const mcg::Error& e) {
    EXPECT_EQ(std::string(e.what()), "--plant: parentheses nested deeper than 200 at character 203");
  }
  const std::string at_limit = std::string(200, '(') + "s+1" + std::string(200, ')');
  EXPECT_EQ(trim(parse_tf("1/" + at_limit, "t").tf.den).size(), 2u);
  // A chain of signs is counted in a loop: 60,000 of them cost no stack.
  const Tf even = parse_tf("1/" + std::string(60000, '-') + "(s+1)", "t").tf;
  EXPECT_GT(even.eval(Complex(0.0, 0.0)).real(), 0.0);
  const Tf odd = parse_tf("1/" + std::string(59999, '-') + "(s+1)", "t").tf;
  EXPECT_LT(odd.eval(Complex(0.0, 0.0)).real(), 0.0);
  try {
    (void)parse_tf("1/" + std::string(120000, '-') + "(s+1)", "[plant] tf");
    FAIL() << "120,000 signs were read";
  } catch (const mcg::Error& e) {
    EXPECT_EQ(std::string(e.what()), "[plant] tf: expression of 120007 characters above the limit of 65536");
  }
}

}  // namespace
}  // namespace mcg::linsys
