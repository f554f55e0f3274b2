// Unit tests of the CSV reader and writer against the data contract.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "common/error.hpp"
#include "common/text.hpp"
#include "table/table.hpp"
#include "test_support_error.hpp"

namespace mcg::table {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

Table parse(const std::string& text) {
  std::istringstream in(text);
  return read(in, "in.csv");
}

std::string error_of(const std::string& text) {
  return test::error_of([&] { parse(text); });
}

TEST(TableRead, MetadataHeaderAndRows) {
  const Table t = parse("# source: test 1\n# sample_period: 0.001\nt,v\n0,1.5\n0.001,2e-3\n");
  EXPECT_EQ(t.meta.get("source"), "test 1");
  EXPECT_EQ(t.meta.get("sample_period"), "0.001");
  EXPECT_FALSE(t.meta.get("seed").has_value());
  EXPECT_THAT(t.names, ElementsAre("t", "v"));
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_DOUBLE_EQ(t.col("v")[1], 0.002);
  EXPECT_EQ(t.line_of(0), 4u);
}

TEST(TableRead, InfNanEmptyAndCrlf) {
  const Table t = parse("t,r_load,i\r\n0,inf,\r\n1,-inf,nan\r\n2,+3,NaN\r\n");
  ASSERT_EQ(t.rows(), 3u);
  EXPECT_TRUE(std::isinf(t.col("r_load")[0]) && t.col("r_load")[0] > 0);
  EXPECT_TRUE(std::isinf(t.col("r_load")[1]) && t.col("r_load")[1] < 0);
  EXPECT_TRUE(std::isnan(t.col("i")[0]));
  EXPECT_TRUE(std::isnan(t.col("i")[1]));
  EXPECT_DOUBLE_EQ(t.col("r_load")[2], 3.0);
}

TEST(TableRead, LastLineWithoutNewline) {
  const Table t = parse("t\n1\n2");
  EXPECT_THAT(t.col("t"), ElementsAre(1.0, 2.0));
}

TEST(TableRead, ErrorsNameLineColumnAndText) {
  EXPECT_EQ(error_of(""), "in.csv: empty input: no header line");
  EXPECT_EQ(error_of("# only: metadata\n"), "in.csv: empty input: no header line");
  EXPECT_EQ(error_of("t,rpm\n0,1\n1,3a\n"), "in.csv:3: column 'rpm': invalid number '3a'");
  EXPECT_EQ(error_of("t,rpm\n0,1,2\n"), "in.csv:2: more fields than the 2 columns of the header");
  EXPECT_EQ(error_of("t,rpm\n0\n"), "in.csv:2: 1 field, the header has 2 columns");
  EXPECT_EQ(error_of("t,t\n"), "in.csv:1: header: duplicate column 't'");
  EXPECT_EQ(error_of("t,,v\n"), "in.csv:1: header: empty column name (column 2)");
  EXPECT_EQ(error_of("0,1\n"), "in.csv:1: header: expected column names, found the number '0'");
  EXPECT_EQ(error_of("t,v\n0,1\n\n1,2\n"), "in.csv:3: empty line, the header has 2 columns");
  EXPECT_EQ(error_of("t,v\n0,1\n# late: meta\n"), "in.csv:3: metadata line after the header");
}

// A name is written back as read: a control character in it (a CR inside one reached the
// Writer's MCG_DEMAND, an abort of mcg-sim) is refused where it is read.
TEST(TableRead, AColumnNameHoldsNoControlCharacter) {
  EXPECT_EQ(error_of("t,v,x\ry\n0,1,2\n"),
            "in.csv:1: header: column name 'x\\x0dy' holds a control character");
  EXPECT_EQ(error_of("# a: b\nt,v\x1b[2J\n"),
            "in.csv:2: header: column name 'v\\x1b[2J' holds a control character");
  EXPECT_EQ(parse("t,\xcf\x89\r\n0,1\r\n").names, (std::vector<std::string>{"t", "\xcf\x89"}));
}

// Where a metadata value came from, for a message about it.
TEST(TableRead, MetadataKnowsItsLines) {
  const Table t = parse("# a: 1\n\n# b: 2\n# a: 3\nt\n0\n");
  EXPECT_EQ(t.meta.where("in.csv", "a"), "in.csv:4");
  EXPECT_EQ(t.meta.where("in.csv", "b"), "in.csv:3");
  EXPECT_EQ(t.meta.where("in.csv", "c"), "in.csv");
}

TEST(TableRead, MissingColumnListsWhatThereIs) {
  const Table t = parse("t,rpm\n0,1\n");
  try {
    (void)t.col("v");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "in.csv: missing column 'v' (has: t,rpm)");
  }
}

TEST(TableRead, RequireIncreasingAndFinite) {
  EXPECT_NO_THROW(require_increasing(parse("t\n0\n0.5\n1\n"), "t"));
  try {
    require_increasing(parse("t\n0\n0.5\n0.5\n"), "t");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "in.csv:4: column 't': 0.5 does not increase (previous row: 0.5)");
  }
  try {
    require_finite(parse("t,v\n0,1\n1,nan\n"), "v");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "in.csv:3: column 'v': an unmeasured value (nan or empty) is not allowed here");
  }
}

TEST(TableRead, StreamingReaderAcrossBlockBoundaries) {
  std::string text = "t,x\n";
  for (int i = 0; i < 200000; ++i) text += std::to_string(i) + "," + std::to_string(i * 2) + "\n";
  std::istringstream in(text);
  Reader r(in, "big");
  const std::size_t x = r.require("x");
  long long n = 0;
  while (r.next()) {
    ASSERT_EQ(r[x], 2.0 * static_cast<double>(n));
    ++n;
  }
  EXPECT_EQ(n, 200000);
}

// A large table (over 4 MiB a core) is parsed in parts, one a core: the rows come out in order,
// the same as the streaming Reader's, CRLF and a last line without a newline included, and
// an error names the first bad line of the whole input, whichever part holds it.
std::string big_table(std::size_t rows) {
  std::string text = "# source: test\n# sample_period: 0.001\nt,n,m\n";
  for (std::size_t k = 0; k < rows; ++k) {
    text += fmt::format("{},{},{}{}", 0.001 * static_cast<double>(k), k, -static_cast<double>(k) / 3.0,
                        k % 7 == 0 ? "\r\n" : "\n");
  }
  text.pop_back();  // the last line without its newline
  return text;
}

TEST(TableRead, LargeTableInPartsMatchesTheStreamingReader) {
  const std::size_t n = 600000;  // about 18 MB
  const std::string text = big_table(n);
  const Table t = parse(text);
  ASSERT_EQ(t.rows(), n);
  EXPECT_EQ(t.first_line, 4U);
  std::istringstream in(text);
  Reader r(in, "in.csv");
  for (std::size_t k = 0; k < n; ++k) {
    ASSERT_TRUE(r.next());
    ASSERT_EQ(t.columns[1][k], static_cast<double>(k));
    ASSERT_EQ(t.columns[0][k], r[0]);
    ASSERT_EQ(t.columns[2][k], r[2]);
  }
  EXPECT_FALSE(r.next());
}

// A row of plain decimals is read in one pass; every other row field by field. Either way each
// field reads as parse_number reads it alone, and a bad row gets the message of its first fault:
// rows of plain, padded, exponent, signed, empty, malformed fields, too few and too many.
TEST(TableRead, RowsReadAsTheirFieldsAlone) {
  const std::vector<std::string> forms{"0",
                                       "-0",
                                       "12.5",
                                       "-3",
                                       "0.001",
                                       "5.6",
                                       " 7",
                                       "8 ",
                                       "1e3",
                                       "+4",
                                       "inf",
                                       "",
                                       "nan",
                                       "12345678901234567890",
                                       "0.12345678901234567890123",
                                       "5.",
                                       ".5",
                                       "3a",
                                       "-",
                                       "1.2.3",
                                       "9007199254740993",
                                       "#"};
  std::mt19937_64 rng(22);
  for (int n = 0; n < 4000; ++n) {
    // Mostly plain rows, which take the one-pass path up to the field that leaves it.
    const std::size_t fields = n % 10 == 0 ? 1 + rng() % 5 : 3;
    std::vector<std::string> cells;
    std::string line;
    for (std::size_t k = 0; k < fields; ++k) {
      cells.push_back(forms[rng() % (n % 3 == 0 ? forms.size() : 6)]);
      line += (k ? "," : "") + cells.back();
    }
    // The message of the row's first fault, field by field as the contract states them.
    std::string fault;
    std::vector<double> want(3);
    const std::string_view trimmed = trim_line(line);
    if (!trimmed.empty() && trimmed.front() == '#') {
      fault = "metadata line after the header";
    } else if (trimmed.empty()) {
      fault = "empty line, the header has 3 columns";
    } else {
      for (std::size_t k = 0; k < fields && fault.empty(); ++k) {
        if (k >= 3) {
          fault = "more fields than the 3 columns of the header";
        } else if (!parse_number(cells[k], want[k])) {
          fault = fmt::format("column '{}': invalid number '{}'", "abc"[k], trim_line(cells[k]));
        }
      }
      if (fault.empty() && fields != 3)
        fault = fmt::format("{} field{}, the header has 3 columns", fields, fields == 1 ? "" : "s");
    }
    const std::string text = "a,b,c\n" + line + "\n";
    if (!fault.empty()) {
      ASSERT_EQ(error_of(text), "in.csv:2: " + fault) << line;
      continue;
    }
    const Table t = parse(text);
    ASSERT_EQ(t.rows(), 1U) << line;
    for (std::size_t c = 0; c < 3; ++c) {
      ASSERT_EQ(std::isnan(t.columns[c][0]), std::isnan(want[c])) << line;
      if (!std::isnan(want[c])) {
        ASSERT_EQ(std::bit_cast<std::uint64_t>(t.columns[c][0]), std::bit_cast<std::uint64_t>(want[c]))
            << line;
      }
    }
  }
}

// A line longer than a part (5 MiB of blanks before a value) is read whole.
TEST(TableRead, LineLongerThanAPart) {
  const std::string text = "t,v\n0,1\n" + std::string(5U << 20, ' ') + "1,2\n2,3\n";
  const Table t = parse(text);
  EXPECT_THAT(t.columns[0], ElementsAre(0.0, 1.0, 2.0));
  EXPECT_THAT(t.columns[1], ElementsAre(1.0, 2.0, 3.0));
}

TEST(TableRead, LargeTableNamesTheFirstBadLine) {
  std::string text = big_table(600000);
  // Line 500003 holds row 499999, in the input's last part; line 12 holds row 8, in its first.
  const auto line_start = [&](std::size_t line) {
    std::size_t pos = 0;
    for (std::size_t l = 1; l < line; ++l) pos = text.find('\n', pos) + 1;
    return pos;
  };
  std::string late = text;
  late.replace(line_start(500003), 1, "x");
  EXPECT_EQ(error_of(late), "in.csv:500003: column 't': invalid number 'x99.999'");
  std::string both = late;
  both.insert(line_start(12), "1,");
  EXPECT_EQ(error_of(both), "in.csv:12: more fields than the 3 columns of the header");
  std::string tail = text + "\n# late metadata";
  EXPECT_EQ(error_of(tail), "in.csv:600004: metadata line after the header");
}

TEST(TableWrite, RoundTripKeepsMetadataAndValues) {
  const Table t = parse("# seed: 42\nt,v,r_load\n0,1.25,inf\n0.001,-2,nan\n");
  std::ostringstream out;
  write(out, t);
  EXPECT_EQ(out.str(), "# seed: 42\nt,v,r_load\n0,1.25,inf\n0.001,-2,nan\n");
}

// A wide table (mcg-sim --compare writes 17 columns) keeps every name: the header is data, not
// the shortened column list of a message.
TEST(TableWrite, WideHeaderRoundTrips) {
  std::string csv = "c0";
  std::string row = "0";
  for (int c = 1; c < 30; ++c) {
    csv += ",c" + std::to_string(c);
    row += "," + std::to_string(c);
  }
  csv += "\n" + row + "\n";
  std::ostringstream out;
  write(out, parse(csv));
  EXPECT_EQ(out.str(), csv);
}

TEST(TableWrite, DigitsPerColumn) {
  std::ostringstream out;
  Writer w(out);
  w.header({"t", "rpm"});
  w.set_digits("rpm", 4);
  w.row({0.1 + 0.2, 1234.5678});
  w.finish();
  EXPECT_EQ(out.str(), "t,rpm\n0.3,1235\n");
}

// Every number is written as printf's "%.Ng" (std::to_chars general with N digits), whichever
// path formats it: values from each decade, random bit patterns, and values a hair from a
// rounding midpoint at 10 digits (where a scaled double could round the wrong way).
TEST(TableWrite, NumbersAreExactlyPrintfG) {
  std::mt19937_64 rng(15);
  std::uniform_real_distribution<double> decade(-8.0, 18.0);
  std::vector<double> values{1.0,
                             -1.0,
                             0.5,
                             9.9999999995,
                             9.9999999994999,
                             99999.999995,
                             1e-4,
                             9.99999999995e-5,
                             0.00010000000005,
                             1e10,
                             9999999999.5,
                             9999999999.4999,
                             123456789012345.0,
                             1e15,
                             0.1 + 0.2,
                             1e-300,
                             5e-324,
                             -1.7976931348623157e308};
  // Integers, printed on their own path: every width, and at each power of ten.
  for (double x = 1.0; x <= 1e10; x *= 10.0) {
    for (double v : {x - 1.0, x, x + 1.0, 2.0 * x, 9.0 * x + 7.0}) {
      if (v != 0.0) values.insert(values.end(), {v, -v});
    }
  }
  for (int n = 0; n < 60000; ++n) {
    values.push_back(std::pow(10.0, decade(rng)) * ((rng() & 1U) != 0U ? -1.0 : 1.0));
    const std::uint64_t bits = rng();
    double any = 0.0;
    std::memcpy(&any, &bits, sizeof any);
    if (std::isfinite(any) && any != 0.0) values.push_back(any);
    // a 10-digit midpoint times a power of ten, and its neighbours
    const double mid = (static_cast<double>(rng() % 10000000000ULL) + 0.5) *
                       std::pow(10.0, static_cast<double>(rng() % 20) - 14.0);
    values.push_back(mid);
    values.push_back(std::nextafter(mid, 0.0));
    values.push_back(std::nextafter(mid, 1e300));
  }
  for (int digits = 1; digits <= 17; ++digits) {
    std::ostringstream out;
    Writer w(out);
    w.header({"x"});
    w.set_digits(std::size_t{0}, digits);
    for (double v : values) w.row({v});
    w.finish();
    std::istringstream in(out.str());
    std::string line;
    std::getline(in, line);
    for (double v : values) {
      std::getline(in, line);
      std::array<char, 40> want{};
      char* end =
          std::to_chars(want.data(), want.data() + want.size(), v, std::chars_format::general, digits).ptr;
      ASSERT_EQ(line, std::string(want.data(), end))
          << "digits " << digits << ", value " << fmt::format("{}", v);
    }
  }
}

// A column keeps its last number's text and copies it when the number repeats: each row is
// still every value's own "%.Ng", through runs of repeats, a -0 after a 0, a value back after
// another, nan and inf, and digits changed between rows.
TEST(TableWrite, RepeatedNumbersWriteAsTheirOwnText) {
  const auto g = [](double v, int digits) {
    std::array<char, 40> buf{};
    if (std::isnan(v)) return std::string("nan");
    if (v == 0.0) return std::string("0");  // -0 too: the contract writes a zero as 0
    return std::string(
        buf.data(),
        std::to_chars(buf.data(), buf.data() + buf.size(), v, std::chars_format::general, digits).ptr);
  };
  std::mt19937_64 rng(8);
  const std::vector<double> pool{0.0,
                                 -0.0,
                                 1.0,
                                 -2.5,
                                 12.0,
                                 0.1 + 0.2,
                                 1234.56789012345,
                                 -1e-300,
                                 5.6,
                                 std::numeric_limits<double>::infinity(),
                                 std::numeric_limits<double>::quiet_NaN(),
                                 -std::numeric_limits<double>::infinity(),
                                 123456789012.0,
                                 9.87654321e-5};
  std::ostringstream out;
  Writer w(out);
  w.header({"a", "b", "c"});
  std::string want = "a,b,c\n";
  std::array<double, 3> row{};
  std::array<int, 3> digits{10, 10, 10};
  for (int n = 0; n < 20000; ++n) {
    for (std::size_t c = 0; c < row.size(); ++c) {
      if (rng() % 4 == 0) row[c] = pool[rng() % pool.size()];  // else the value above repeats
    }
    if (n % 997 == 0) {
      const std::size_t c = rng() % row.size();
      digits[c] = 1 + static_cast<int>(rng() % 17);
      w.set_digits(c, digits[c]);
    }
    w.row(row);
    want += fmt::format("{},{},{}\n", g(row[0], digits[0]), g(row[1], digits[1]), g(row[2], digits[2]));
  }
  w.finish();
  EXPECT_EQ(out.str(), want);
}

TEST(TableWrite, FullDeviceIsAnError) {
  std::ofstream full("/dev/full");
  if (!full) GTEST_SKIP() << "no /dev/full";
  Writer w(full, "<stdout>");
  w.header({"x"});
  for (int i = 0; i < 100000; ++i) w.row({1.0});
  try {
    w.finish();
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("writing <stdout>: No space left on device"));
  }
}

TEST(ParseNumber, Forms) {
  double v = 0;
  EXPECT_TRUE(parse_number(" 1e3 ", v));
  EXPECT_EQ(v, 1000.0);
  EXPECT_TRUE(parse_number("-INF", v));
  EXPECT_TRUE(std::isinf(v));
  EXPECT_TRUE(parse_number("1e999", v));
  EXPECT_TRUE(std::isinf(v));
  EXPECT_FALSE(parse_number("1,5", v));
  EXPECT_FALSE(parse_number("0x10", v));
  EXPECT_FALSE(parse_number("--1", v));
  EXPECT_FALSE(parse_number("1.5V", v));
}

TEST(ParseNumber, PlainDecimalsReadAsFromChars) {
  // Plain decimals take a fast path (an integer over an exact power of ten): every one must read
  // bit for bit as std::from_chars reads it, at the path's edges (2^53, 19 digits, 22 decimals)
  // and on random values printed as a simulator and a hand would print them.
  std::vector<std::string> texts{"0",
                                 "-0",
                                 "0.001",
                                 "5.6",
                                 "-12",
                                 "9007199254740992",
                                 "9007199254740993",
                                 "1234567890123456789",
                                 "12345678901234567890",
                                 "0.1234567890123456789012",
                                 "0.12345678901234567890123",
                                 "00000000000000000000001.5",
                                 "5.",
                                 ".5",
                                 "+5",
                                 "+-5",
                                 "-",
                                 "1.2.3",
                                 "1-2"};
  std::mt19937_64 rng(28);
  std::uniform_real_distribution<double> decade(-6.0, 16.0);
  for (int n = 0; n < 20000; ++n) {
    const double x = std::pow(10.0, decade(rng)) * ((rng() & 1U) != 0U ? -1.0 : 1.0);
    texts.push_back(fmt::format("{:.{}g}", x, 1 + static_cast<int>(rng() % 17)));
    texts.push_back(fmt::format("{:.{}f}", x, static_cast<int>(rng() % 24)));
  }
  for (const std::string& text : texts) {
    const char* first = text.data() + (text.starts_with('+') ? 1 : 0);
    double want = 0.0;
    const auto [ptr, ec] = std::from_chars(first, text.data() + text.size(), want);
    const bool ok = ec == std::errc() && ptr == text.data() + text.size();
    double got = 0.0;
    ASSERT_EQ(parse_number(text, got), ok) << text;
    if (ok) {
      ASSERT_EQ(std::bit_cast<std::uint64_t>(got), std::bit_cast<std::uint64_t>(want)) << text;
    }
  }
}

}  // namespace
}  // namespace mcg::table
