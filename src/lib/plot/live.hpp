// mcg-plot-gnuplot --live: a scrolling window of a table that arrives row by row.
#pragma once

#include <cstddef>
#include <deque>
#include <string>
#include <vector>

#include "table/table.hpp"

namespace mcg::plot {

/// The last `window` units of x of a stream of rows (all columns), in memory that does not
/// grow with the stream: a row leaves when the newest x is more than `window` past it.
class RingWindow {
 public:
  RingWindow(std::vector<std::string> names, std::size_t x_column, double window);

  /// Appends a row (one value per name). x must not decrease: throws mcg::Error naming
  /// `where` otherwise.
  void push(const std::vector<double>& row, const std::string& where);
  std::size_t size() const { return m_rows.size(); }
  /// Rows pushed since the start.
  std::size_t pushed() const { return m_pushed; }
  /// The window as a table named `source`, with `meta`.
  table::Table table(const std::string& source, const table::Metadata& meta) const;

 private:
  std::vector<std::string> m_names;
  std::size_t m_x;
  double m_window;
  std::deque<std::vector<double>> m_rows;
  std::size_t m_pushed = 0;
};

}  // namespace mcg::plot
