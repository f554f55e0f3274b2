// Unit tests of the plans of mcg-serial load and send: the controller's registers staged, the
// commits where they belong.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "config/ini.hpp"
#include "link/serial.hpp"
#include "mcg_protocol.h"
#include "table/table.hpp"
#include "test_support_error.hpp"

namespace mcg::link {
namespace {

LoadPlan plan_of(const std::string& text) {
  std::istringstream in(text);
  return load_plan(config::Ini::parse(in, "b.ini"), "b.ini");
}

std::vector<SeqEntry> send_of(const std::string& csv) {
  std::istringstream in(csv);
  return send_plan(table::read(in, "s.csv"), 8);
}

// The controller's registers come first (coef_frac before the gains it scales): load stages them
// and commits once, then writes the rest.
TEST(LinkSerial, LoadStagesTheControllerFirst) {
  const LoadPlan plan = plan_of("[board]\nrpm_cmd = 500\nkp = 2\nmode = p\nclutch = 2\ncoef_frac = 10\n");
  std::vector<std::string> names;
  for (const LoadWrite& w : plan) names.emplace_back(w.reg->name);
  EXPECT_EQ(names, (std::vector<std::string>{"coef_frac", "kp", "mode", "rpm_cmd", "clutch"}));
}

TEST(LinkSerial, LoadRefusesTheCommitRegister) {
  EXPECT_EQ(test::error_of([] { plan_of("[board]\ncommit = 1\n"); }),
            "b.ini:2: [board] commit: an action, not a setting (load commits itself)");
}

// A row that changes controller registers gets one commit right after its changes, at the same time;
// rows changing only the command get none.
TEST(LinkSerial, SendCommitsEachRowOfControllerChanges) {
  const std::vector<SeqEntry> e = send_of("t,rpm_cmd,b0,mode\n0,400,1,2\n0.5,450,1,2\n1,450,2,3\n");
  ASSERT_EQ(e.size(), 8u);
  const std::vector<std::uint8_t> regs{MCG_REG_RPM_CMD, MCG_REG_B0, MCG_REG_MODE, MCG_REG_COMMIT,
                                       MCG_REG_RPM_CMD, MCG_REG_B0, MCG_REG_MODE, MCG_REG_COMMIT};
  for (std::size_t k = 0; k < e.size(); ++k) EXPECT_EQ(e[k].reg, regs[k]) << k;
  EXPECT_EQ(e[3].delay_ms, 0);
  EXPECT_EQ(e[3].raw, 1);
  EXPECT_EQ(e[4].delay_ms, 500);
  EXPECT_EQ(e[5].delay_ms, 500);
  EXPECT_EQ(e[5].raw, 512);  // b0 = 2 at F = 8
  EXPECT_EQ(e[7].delay_ms, 0);
}

}  // namespace
}  // namespace mcg::link
