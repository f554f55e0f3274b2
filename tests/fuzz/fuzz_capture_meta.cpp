// A capture's metadata as mcg-sim reads it (mcg-csv(5)): board_config, rpm_estimator and
// i_measurement. Every board_config that parses must be one the firmware core takes: its
// registers written at power-on (a refusal is an MCG_DEMAND abort) and the loop run a few ticks.
#include "fuzz.hpp"
#include "link/capture_meta.hpp"
#include "measurement/measurement.hpp"
#include "mcg_protocol.h"
#include "sim/controller.hpp"
#include "table/table.hpp"

#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(mcg::fuzz::text_of(data, size));
  try {
    std::istringstream in(text);
    mcg::table::Reader reader(in, "<fuzz>");
    const mcg::table::Metadata& meta = reader.metadata();
    for (const char* key : {"rpm_estimator", "i_measurement"}) {
      const auto value = meta.get(key);
      if (!value) continue;
      try {
        if (std::string_view(key) == "rpm_estimator") {
          (void)mcg::measurement::parse_rpm_estimator(*value);
        } else {
          (void)mcg::measurement::parse_i_measurement(*value);
        }
      } catch (const mcg::Error& e) {
        mcg::fuzz::check_message(e);
      }
    }
    const auto board = mcg::link::captured_board(meta, reader.source());
    if (board && board->mode != MCG_MODE_OPEN) {
      const auto loop = mcg::sim::board_loop_controller(board->mode, board->registers);
      for (int k = 0; k < 4; ++k) (void)loop->tick(0.01 * k, 420.0);
    }
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
  }
  return 0;
}
