// mcg-serial's file readers without a board: the send CSV (register columns over t to the
// command sequence) and the load INI ([board] registers and [controller]).
#include "config/ini.hpp"
#include "fuzz.hpp"
#include "link/serial.hpp"
#include "table/table.hpp"

#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(mcg::fuzz::text_of(data, size));
  try {
    std::istringstream in(text);
    const mcg::table::Table tbl = mcg::table::read(in, "seq.csv");
    for (int frac = 0; frac <= 12; frac += 6) {
      const auto entries = mcg::link::send_plan(tbl, frac);
      if (entries.size() > MCG_SEQ_MAX) mcg::fuzz::finding("send_plan exceeded the board's sequence");
    }
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
  }
  try {
    std::istringstream in(text);
    const auto plan = mcg::link::load_plan(mcg::config::Ini::parse(in, "board.ini"), "board.ini");
    for (const auto& w : plan) {
      if (w.reg == nullptr || !w.reg->writable) mcg::fuzz::finding("load_plan writes a read-only register");
    }
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
  }
  return 0;
}
