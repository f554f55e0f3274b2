// The CSV writer and reader (mcg-csv(5)): whatever the reader accepts, the writer writes (17
// digits) and the reader reads back to the same metadata, names and numbers (17 digits: exactly).
#include "fuzz.hpp"
#include "table/table.hpp"

#include <cmath>
#include <sstream>
#include <string>

namespace {

/// The same number: equal (the writer prints -0 as 0, the same value), or both nan.
bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(mcg::fuzz::text_of(data, size));
  mcg::table::Table first;
  try {
    std::istringstream in(text);
    first = mcg::table::read(in, "<fuzz>");
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
    return 0;
  }
  std::ostringstream written;
  mcg::table::write(written, first, 17);
  mcg::table::Table again;
  try {
    std::istringstream in(written.str());
    again = mcg::table::read(in, "<written>");
  } catch (const mcg::Error& e) {
    std::fprintf(stderr, "fuzz: %s\n", e.what());
    mcg::fuzz::finding("the reader refuses what the writer wrote");
  }
  if (again.names != first.names) mcg::fuzz::finding("the round trip changes the names");
  if (again.meta.entries() != first.meta.entries()) mcg::fuzz::finding("the round trip changes the metadata");
  if (again.rows() != first.rows()) mcg::fuzz::finding("the round trip changes the row count");
  for (std::size_t c = 0; c < first.columns.size(); ++c) {
    for (std::size_t r = 0; r < first.rows(); ++r) {
      if (!same(first.columns[c][r], again.columns[c][r]))
        mcg::fuzz::finding("the round trip changes a number");
    }
  }
  return 0;
}
