// Unit tests of the INI parameter sets.
#include "common/error.hpp"
#include "config/ini.hpp"
#include "test_support_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

namespace mcg::config {
namespace {

Ini parse(const std::string& text, const std::string& name = "p.ini") {
  std::istringstream in(text);
  return Ini::parse(in, name);
}

std::string error_of(const std::string& text) {
  return test::error_of([&] { parse(text); });
}

TEST(Ini, SectionsKeysCommentsAndNumbers) {
  const Ini ini = parse("top = 1\n; comment\n[motor]\nR_ohm = 3.91  ; winding\n# other\nL_H=4.1e-3\n[load]\nr = inf\n");
  EXPECT_EQ(ini.number("", "top"), 1.0);
  EXPECT_EQ(ini.number("motor", "R_ohm"), 3.91);
  EXPECT_EQ(ini.number("motor", "L_H"), 4.1e-3);
  EXPECT_TRUE(std::isinf(*ini.number("load", "r")));
  EXPECT_FALSE(ini.number("motor", "Kt").has_value());
  EXPECT_EQ(ini.number_or("motor", "Kt", 0.0582), 0.0582);
  EXPECT_EQ(ini.sections(), (std::vector<std::string>{"", "motor", "load"}));
}

TEST(Ini, NumberListsAndBadValuesNameTheLine) {
  const Ini ini = parse("[controller]\nb = 11.645 -6.987\na = 1, -1\nk = 3x\n");
  EXPECT_EQ(*ini.numbers("controller", "b"), (std::vector<double>{11.645, -6.987}));
  EXPECT_EQ(*ini.numbers("controller", "a"), (std::vector<double>{1, -1}));
  try {
    (void)ini.number("controller", "k");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "p.ini:4: [controller] k: invalid number '3x'");
  }
}

TEST(Ini, SyntaxErrors) {
  EXPECT_EQ(error_of("[motor\n"), "p.ini:1: section header without ']'");
  EXPECT_EQ(error_of("[]\n"), "p.ini:1: empty section name");
  EXPECT_EQ(error_of("[a]\njust words\n"), "p.ini:2: expected 'key = value', found 'just words'");
  EXPECT_EQ(error_of("[a]\nx = 1\nx = 2\n"), "p.ini:3: [a] x: given twice (first at p.ini:2)");
}

TEST(Ini, LaterFilesWinAndWriteReadsBack) {
  Ini a = parse("[m]\nR = 1\nL = 2\n", "a.ini");
  a.merge(parse("[m]\nR = 5\n[n]\nx = 3\n", "b.ini"));
  EXPECT_EQ(a.number("m", "R"), 5.0);
  EXPECT_EQ(a.find("m", "R")->origin, "b.ini:2");
  a.set("n", "y", 0.1, "why");
  const std::string text = a.str();
  EXPECT_EQ(text, "[m]\nR = 5\nL = 2\n\n[n]\nx = 3\ny = 0.1  ; why\n");
  const Ini back = parse(text);
  EXPECT_EQ(back.number("n", "y"), 0.1);
}

TEST(Ini, FormatNumberRoundTrips) {
  EXPECT_EQ(format_number(0.1), "0.1");
  EXPECT_EQ(format_number(1.0 / 3.0), "0.3333333333333333");
  EXPECT_EQ(format_number(-INFINITY), "-inf");
}

}  // namespace
}  // namespace mcg::config
