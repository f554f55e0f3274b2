// The scrolling window of mcg-plot-gnuplot --live.
#include "plot/live.hpp"

#include <cmath>

#include "common/demand.hpp"
#include "common/error.hpp"

namespace mcg::plot {

RingWindow::RingWindow(std::vector<std::string> names, std::size_t x_column, double window)
    : m_names(std::move(names)), m_x(x_column), m_window(window) {
  MCG_DEMAND(m_x < m_names.size() && window > 0.0);
}

void RingWindow::push(const std::vector<double>& row, const std::string& where) {
  MCG_DEMAND(row.size() == m_names.size());
  const double x = row[m_x];
  if (!std::isfinite(x)) fail("{}: column {}: {} is not a finite number", where, quote(m_names[m_x]), x);
  if (!m_rows.empty() && x < m_rows.back()[m_x]) {
    fail("{}: column {} goes back ({} after {}): a live plot needs it increasing", where, quote(m_names[m_x]),
         x, m_rows.back()[m_x]);
  }
  m_rows.push_back(row);
  ++m_pushed;
  while (m_rows.front()[m_x] < x - m_window) m_rows.pop_front();
}

table::Table RingWindow::table(const std::string& source, const table::Metadata& meta) const {
  table::Table t;
  t.source = source;
  t.meta = meta;
  t.names = m_names;
  t.columns.assign(m_names.size(), {});
  for (auto& c : t.columns) c.reserve(m_rows.size());
  for (const auto& row : m_rows) {
    for (std::size_t k = 0; k < row.size(); ++k) t.columns[k].push_back(row[k]);
  }
  return t;
}

}  // namespace mcg::plot
