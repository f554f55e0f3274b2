// The CSV table reader (mcg-csv(5)) with the checks tools apply to it; both the whole-table
// and the streaming reader must agree on what they accept.
#include "fuzz.hpp"
#include "table/table.hpp"

#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(mcg::fuzz::text_of(data, size));
  bool table_ok = false;
  std::size_t table_rows = 0;
  try {
    std::istringstream in(text);
    const mcg::table::Table tbl = mcg::table::read(in, "<fuzz>");
    table_ok = true;
    table_rows = tbl.rows();
    for (const auto& name : tbl.names) {
      if (tbl.col(name).size() != tbl.rows()) mcg::fuzz::finding("a column's length differs from rows()");
      try {
        mcg::table::require_finite(tbl, name);
        mcg::table::require_increasing(tbl, name);
      } catch (const mcg::Error& e) {
        mcg::fuzz::check_message(e);
      }
    }
    try {
      (void)tbl.col("t");
    } catch (const mcg::Error& e) {
      mcg::fuzz::check_message(e);
    }
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
  }
  bool stream_ok = false;
  std::size_t stream_rows = 0;
  try {
    std::istringstream in(text);
    mcg::table::Reader r(in, "<fuzz>");
    while (r.next()) ++stream_rows;
    stream_ok = true;
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
  }
  if (table_ok != stream_ok || (table_ok && table_rows != stream_rows)) {
    mcg::fuzz::finding("table::read and table::Reader disagree");
  }
  return 0;
}
