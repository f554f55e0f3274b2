// The board's `# excitation:` line: written and read back, and told apart from mcg-sweep's prose.
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "measurement/board_excitation.hpp"

namespace {

using mcg::measurement::BoardExcitation;
using mcg::measurement::format_board_excitation;
using mcg::measurement::parse_board_excitation;

TEST(BoardExcitation, ChirpLineReadsBack) {
  BoardExcitation e;
  e.kind = "chirp";
  e.column = "duty";
  e.values = {{"f0", 0.5},  {"f1", 20},    {"sweep", 4},  {"update", 0.001},
              {"amp", 0.2}, {"bias", 0.4}, {"periods", 1}};
  const std::string text = format_board_excitation(e);
  EXPECT_EQ(text, "chirp column=duty f0=0.5 f1=20 sweep=4 update=0.001 amp=0.2 bias=0.4 periods=1");
  const auto back = parse_board_excitation(text, "x.csv:1");
  ASSERT_TRUE(back);
  EXPECT_EQ(back->kind, "chirp");
  EXPECT_EQ(back->column, "duty");
  EXPECT_EQ(back->values, e.values);
  EXPECT_EQ(back->value("f1"), 20.0);
  EXPECT_FALSE(back->value("order"));
}

TEST(BoardExcitation, GeneratorProseIsNotTheBoardsLine) {
  EXPECT_FALSE(parse_board_excitation("chirp v 0.5..200 Hz over 20 s, amplitude 2, linear", "x"));
  EXPECT_FALSE(parse_board_excitation("prbs order=9 clock=0.003", "x")) << "no column: not the board's";
  const auto closed =
      parse_board_excitation("prbs column=rpm_cmd order=7 clock=0.01 amp=50 bias=400 periods=1", "x");
  ASSERT_TRUE(closed);
  EXPECT_EQ(closed->column, "rpm_cmd");
}

TEST(BoardExcitation, ABadNumberIsNamed) {
  try {
    parse_board_excitation("chirp column=duty f0=abc", "cap.csv:3");
    FAIL() << "no error";
  } catch (const mcg::Error& e) {
    EXPECT_STREQ(e.what(), "cap.csv:3: excitation: 'f0=abc' is not a number");
  }
}

}  // namespace
