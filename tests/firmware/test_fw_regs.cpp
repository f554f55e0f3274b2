// test_fw_regs.cpp: the register table of mcg-protocol(7) is MCG_REGISTERS, row for row.
//
// The man page's table between ".SH REGISTERS" and ".TE" must hold exactly the rows below,
// generated from the one table in mcg_protocol.h; on a mismatch the test prints the rows to paste.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "mcg_protocol.h"

namespace {

std::string number(long v) { return v < 0 ? "\\-" + std::to_string(-v) : std::to_string(v); }

std::string unit_text(unsigned unit) {
  switch (unit) {
    case MCG_UNIT_MODE:
      return "MCG_MODE_*";
    case MCG_UNIT_SEQ:
      return "MCG_SEQ_*";
    case MCG_UNIT_RPM:
      return "rpm";
    case MCG_UNIT_PERMILLE:
      return "1/1000 (host: %)";
    case MCG_UNIT_GAIN:
      return "Q(F)";
    case MCG_UNIT_BITS:
      return "bits";
    case MCG_UNIT_MS:
      return "ms";
    case MCG_UNIT_COUNT:
      return "count";
    case MCG_UNIT_SWITCH:
      return "0/1";
    case MCG_UNIT_CLUTCH:
      return "MCG_CLUTCH_*";
    case MCG_UNIT_EXC:
      return "MCG_EXC_*";
    case MCG_UNIT_LEVEL:
      return "duty 1/1000 or rpm";
    case MCG_UNIT_CHZ:
      return "1/100 Hz (host: Hz)";
    case MCG_UNIT_S:
      return "s";
    default:
      return "MCG_FLAG_*";
  }
}

std::string access_text(unsigned access) { return access == MCG_RW ? "rw" : access == MCG_RS ? "rs" : "ro"; }

std::string hex_id(unsigned id) {
  static const char digits[] = "0123456789ABCDEF";
  return std::string("0x") + digits[id >> 4] + digits[id & 15u];
}

std::vector<std::string> expected_rows() {
  std::vector<std::string> rows;
#define MAN_ROW(NAME, name, access, lo, hi, def, unit, capture, keypad, doc)                             \
  rows.push_back(hex_id(MCG_REG_##NAME) + "\t" + name + "\t" + access_text(access) + "\t" + number(lo) + \
                 ".." + number(hi) + "\t" + ((access) != MCG_RO ? number(def) : "") + "\t" +             \
                 unit_text(unit) + "\t" + doc);
  MCG_REGISTERS(MAN_ROW)
#undef MAN_ROW
  return rows;
}

std::vector<std::string> man_rows() {
  std::ifstream in(MCG_PROTOCOL_MAN);
  std::vector<std::string> rows;
  std::string line;
  bool section = false;
  bool table = false;
  while (std::getline(in, line)) {
    if (line == ".SH REGISTERS") section = true;
    if (!section) continue;
    if (line == ".TE") break;
    if (line == "_") {
      table = true;
      continue;
    }
    if (table) rows.push_back(line);
  }
  return rows;
}

TEST(FwRegs, ManPageTableIsTheHeaderTable) {
  const std::vector<std::string> expected = expected_rows();
  const std::vector<std::string> man = man_rows();
  std::ostringstream paste;
  for (const std::string& row : expected) paste << row << '\n';
  EXPECT_EQ(man, expected) << "rows for man/mcg-protocol.7, REGISTERS (after the '_' line):\n" << paste.str();
}

// Every frame the EXAMPLES section shows ("PC:" and "board:" lines) is one a decoder accepts: its
// LEN counts its payload and its CRC is right.
TEST(FwRegs, ManPageExampleFramesAreWellFormed) {
  std::ifstream in(MCG_PROTOCOL_MAN);
  std::string line;
  int frames = 0;
  while (std::getline(in, line)) {
    if (line.rfind("PC:", 0) != 0 && line.rfind("board:", 0) != 0) continue;
    std::istringstream bytes(line.substr(line.find(':') + 1));
    std::vector<unsigned> b;
    unsigned v = 0;
    while (bytes >> std::hex >> v) b.push_back(v);
    ASSERT_GE(b.size(), MCG_FRAME_OVERHEAD) << line;
    EXPECT_EQ(b[0], MCG_SYNC) << line;
    EXPECT_EQ(b.size(), b[1] + MCG_FRAME_OVERHEAD) << line;
    unsigned crc = MCG_CRC_INIT;
    for (std::size_t k = 1; k + 2 < b.size(); ++k) crc = mcg_crc16_update(crc, b[k]);
    EXPECT_EQ(crc, b[b.size() - 2] | (b.back() << 8)) << line;
    ++frames;
  }
  EXPECT_GE(frames, 8);
}

TEST(FwRegs, ManPageStatesTheReadManyLimit) {
  std::ifstream in(MCG_PROTOCOL_MAN);
  const std::string page((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string limit = "count u8 (1.." + std::to_string(MCG_READ_MANY_MAX) + ")";
  EXPECT_NE(page.find(limit), std::string::npos) << limit;
  EXPECT_NE(page.find("outside 1.." + std::to_string(MCG_READ_MANY_MAX)), std::string::npos);
}

}  // namespace
