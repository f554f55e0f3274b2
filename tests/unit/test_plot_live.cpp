// The scrolling window of mcg-plot-gnuplot --live: what it keeps, and the rows it refuses.
#include <gtest/gtest.h>

#include "plot/live.hpp"
#include "test_support_error.hpp"

namespace mcg::plot {
namespace {

TEST(PlotLive, KeepsTheLastWindowOfXWhateverTheStreamLength) {
  RingWindow ring({"t", "rpm"}, 0, 1.0);
  for (int n = 0; n <= 100000; ++n) ring.push({n * 1e-3, static_cast<double>(n)}, "test");
  EXPECT_EQ(ring.pushed(), 100001U);
  // t from 99 to 100 s inclusive: 1001 rows, the memory of one window.
  EXPECT_EQ(ring.size(), 1001U);
  const table::Table t = ring.table("stdin", {});
  EXPECT_EQ(t.names, (std::vector<std::string>{"t", "rpm"}));
  EXPECT_DOUBLE_EQ(t.col("t").front(), 99.0);
  EXPECT_DOUBLE_EQ(t.col("rpm").back(), 100000.0);
}

TEST(PlotLive, RefusesXGoingBackOrNotFiniteNamingTheLine) {
  RingWindow ring({"t", "rpm"}, 0, 5.0);
  ring.push({1.0, 2.0}, "stdin:3");
  EXPECT_EQ(test::error_of([&] {
              ring.push({0.5, 2.0}, "stdin:4");
            }),
            "stdin:4: column 't' goes back (0.5 after 1): a live plot needs it increasing");
  EXPECT_EQ(test::error_of([&] {
              ring.push({std::nan(""), 2.0}, "stdin:5");
            }),
            "stdin:5: column 't': nan is not a finite number");
  EXPECT_EQ(ring.size(), 1U);
}

}  // namespace
}  // namespace mcg::plot
