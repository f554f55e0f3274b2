// LineReader: lines handed on as a pipe delivers them, each byte scanned once, a bounded line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <ext/stdio_filebuf.h>
#include <istream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>

#include "common/line_reader.hpp"
#include "config/ini.hpp"
#include "table/table.hpp"
#include "test_support_error.hpp"

namespace mcg {
namespace {

using test::error_of;

// A pipe whose writer sends the header and a row, then keeps the pipe open until the reader
// has the row (or 20 s pass): a reader that waits for a buffer to fill gets the row only
// after the close, and the test sees that.
TEST(CommonLineReader, ARowOnAnOpenPipeArrivesBeforeTheWriterCloses) {
  int fd[2];
  ASSERT_EQ(::pipe(fd), 0);
  std::mutex mutex;
  std::condition_variable cv;
  bool got_row = false;
  std::atomic<bool> closed{false};
  std::thread writer([&] {
    const std::string text = "# source: test\nt,v\n0.5,2\n";
    EXPECT_EQ(::write(fd[1], text.data(), text.size()), static_cast<ssize_t>(text.size()));
    std::unique_lock lock(mutex);
    cv.wait_for(lock, std::chrono::seconds(20), [&] { return got_row; });
    closed = true;
    ::close(fd[1]);
  });
  // The stream buffer std::cin has once a tool stops syncing with stdio.
  __gnu_cxx::stdio_filebuf<char> buf(fd[0], std::ios::in);
  std::istream in(&buf);
  table::Reader reader(in, "<pipe>");
  ASSERT_TRUE(reader.next());
  EXPECT_FALSE(closed.load()) << "the row came only when the writer closed the pipe";
  EXPECT_EQ(reader[1], 2.0);
  {
    const std::lock_guard lock(mutex);
    got_row = true;
  }
  cv.notify_all();
  EXPECT_FALSE(reader.next());
  writer.join();
}

TEST(CommonLineReader, LinesCrlfAndALastLineWithoutNewline) {
  std::istringstream in("a\r\n\nb\nc");
  LineReader lines(in, "x");
  std::string_view line;
  std::vector<std::string> got;
  while (lines.next(line)) got.emplace_back(line);
  EXPECT_EQ(got, (std::vector<std::string>{"a", "", "b", "c"}));
  EXPECT_EQ(lines.line(), 4U);
}

// The limit is exact: a line of k_max_line_bytes reads, one byte more is an error naming the
// line, whether the newline comes or never does, in the streaming and the whole-table reader.
TEST(CommonLineReader, TheLongestLineAndOneByteMore) {
  const std::string longest(k_max_line_bytes, 'x');
  {
    std::istringstream in("t\n" + longest + "\nend\n");
    LineReader lines(in, "in");
    std::string_view line;
    ASSERT_TRUE(lines.next(line));
    ASSERT_TRUE(lines.next(line));
    EXPECT_EQ(line.size(), k_max_line_bytes);
  }
  for (const char* ending : {"\n1\n", ""}) {
    const std::string text = "t\n1\n" + longest + "x" + ending;
    EXPECT_EQ(error_of([&] {
                std::istringstream in(text);
                table::Reader r(in, "in.csv");
                while (r.next()) {
                }
              }),
              "in.csv:3: line longer than 16777216 bytes");
    EXPECT_EQ(error_of([&] {
                std::istringstream in(text);
                table::read(in, "in.csv");
              }),
              "in.csv:3: line longer than 16777216 bytes");
  }
  // A bad row before the long line is the first error, as the streaming reader reports it.
  EXPECT_EQ(error_of([&] {
              std::istringstream in("t\nx\n" + longest + "x");
              table::read(in, "in.csv");
            }),
            "in.csv:2: column 't': invalid number 'x'");
  // A header or INI line that never ends.
  EXPECT_EQ(error_of([&] {
              std::istringstream in("# a: b\n" + longest + "y");
              table::Reader r(in, "in.csv");
            }),
            "in.csv:2: line longer than 16777216 bytes");
  EXPECT_EQ(error_of([&] {
              std::istringstream in("[a]\nk = " + longest);
              config::Ini::parse(in, "c.ini");
            }),
            "c.ini:2: line longer than 16777216 bytes");
}

TEST(CommonLineReader, HeaderColumnLimit) {
  std::string header = "c0";
  for (std::size_t c = 1; c < table::k_max_columns; ++c) header += ",c" + std::to_string(c);
  {
    std::istringstream in(header + "\n");
    table::Reader r(in, "in.csv");
    EXPECT_EQ(r.columns().size(), table::k_max_columns);
  }
  EXPECT_EQ(error_of([&] {
              std::istringstream in("# m: 1\n" + header + ",one_more\n");
              table::Reader r(in, "in.csv");
            }),
            "in.csv:2: header: more than 10000 columns");
  // Duplicates are found however far apart.
  EXPECT_EQ(error_of([&] {
              std::istringstream in(header.substr(0, header.rfind(',')) + ",c1\n");
              table::Reader r(in, "in.csv");
            }),
            "in.csv:1: header: duplicate column 'c1'");
}

// Metadata keeps the first position of a key and its last value, before and after an erase.
TEST(CommonLineReader, MetadataIndexFollowsSetAndErase) {
  std::istringstream in("# a: 1\n# b: 2\n# a: 3\n# c: 4\nt\n");
  table::Metadata meta = table::Reader(in, "in.csv").metadata();
  ASSERT_EQ(meta.entries().size(), 3U);
  EXPECT_EQ(meta.entries()[0], (table::Metadata::Entry{"a", "3"}));
  meta.erase("a");
  meta.set("c", "5");
  meta.set("d", "6");
  EXPECT_EQ(meta.entries(), (std::vector<table::Metadata::Entry>{{"b", "2"}, {"c", "5"}, {"d", "6"}}));
  EXPECT_EQ(meta.get("c"), "5");
  EXPECT_EQ(meta.get("a"), std::nullopt);
}

// The index of an Ini follows parse, merge and set; sections and entries keep their order.
TEST(CommonLineReader, IniIndexFollowsMergeAndSet) {
  std::istringstream a("[s]\nx = 1\ny = 2\n[t]\nz = 3\n");
  std::istringstream b("[t]\nz = 4\n[u]\nw = 5\n[s]\nv = 6\n");
  config::Ini ini = config::Ini::parse(a, "a.ini");
  ini.merge(config::Ini::parse(b, "b.ini"));
  ini.set("s", "x", "7");
  EXPECT_EQ(ini.sections(), (std::vector<std::string>{"s", "t", "u"}));
  EXPECT_EQ(ini.str(), "[s]\nx = 7\ny = 2\nv = 6\n\n[t]\nz = 4\n\n[u]\nw = 5\n");
  EXPECT_EQ(ini.find("t", "z")->origin, "b.ini:2");
  EXPECT_TRUE(ini.has_section("u"));
  EXPECT_FALSE(ini.has_section("v"));
  std::istringstream twice("[s]\nx = 1\n[t]\ny = 1\n[s]\nx = 2\n");
  EXPECT_EQ(error_of([&] { config::Ini::parse(twice, "c.ini"); }),
            "c.ini:6: [s] x: given twice (first at c.ini:2)");
}

}  // namespace
}  // namespace mcg
