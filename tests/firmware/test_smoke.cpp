#include <gtest/gtest.h>

#include "core.h"
#include "host_board.h"

TEST(FirmwareSmoke, ResetState)
{
  host_board_reset();
  host_board_tick(0);
  EXPECT_EQ(host_board_duty(), 0);
}
