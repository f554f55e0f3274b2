// Unit tests of stream block assembly: time axis, the rpm window, held reports, loss counting.
#include "link/stream_block.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "mcg_protocol.h"

namespace mcg::link {
namespace {

std::vector<std::uint8_t> block(std::uint8_t seq, std::int16_t duty, std::int16_t rpm_cmd, std::uint8_t counts) {
  std::vector<std::uint8_t> p{seq};
  p.push_back(static_cast<std::uint8_t>(static_cast<std::uint16_t>(duty) & 0xFF));
  p.push_back(static_cast<std::uint8_t>(static_cast<std::uint16_t>(duty) >> 8));
  p.push_back(static_cast<std::uint8_t>(rpm_cmd & 0xFF));
  p.push_back(static_cast<std::uint8_t>(rpm_cmd >> 8));
  p.insert(p.end(), MCG_STREAM_SAMPLES, counts);
  return p;
}

constexpr double k_block_s = 0.032;

TEST(LinkStreamBlock, TimeAxisWindowAndHeldReports) {
  StreamAssembler a(8);  // 16 ms window, as the board's own rpm register
  ASSERT_TRUE(a.push(block(7, 355, 420, 60), 0.0));
  const auto& rows = a.rows();
  ASSERT_EQ(rows.size(), 16u);
  for (std::size_t k = 0; k < 16; ++k) EXPECT_DOUBLE_EQ(rows[k].t_s, 0.002 * static_cast<double>(k));
  EXPECT_TRUE(std::isnan(rows[6].rpm));  // 7 samples: the window is not full yet
  // 8 samples of 60 pulses in 16 ms: 480 * 1875 / 1024 rpm (the protocol's exact factor).
  EXPECT_DOUBLE_EQ(rows[7].rpm, 480.0 * 1875.0 / 1024.0);
  EXPECT_TRUE(std::isnan(rows[14].duty));  // the report belongs to the block's last sample
  EXPECT_DOUBLE_EQ(rows[15].duty, 0.355);
  EXPECT_DOUBLE_EQ(rows[15].rpm_cmd, 420.0);
  ASSERT_TRUE(a.push(block(8, -20, 300, 61), k_block_s));
  EXPECT_DOUBLE_EQ(a.rows()[0].t_s, 0.032);
  EXPECT_DOUBLE_EQ(a.rows()[0].duty, 0.355);  // held until the next report
  EXPECT_DOUBLE_EQ(a.rows()[15].duty, -0.02);
  EXPECT_DOUBLE_EQ(a.rows()[0].rpm, (7 * 60 + 61) * 1875.0 / 1024.0);
  EXPECT_EQ(a.lost_samples(), 0u);
}

TEST(LinkStreamBlock, SequenceGapsAreLostSamplesAndTimeSkips) {
  StreamAssembler a(8);
  a.push(block(254, 0, 420, 10), 0.0);
  a.push(block(255, 0, 420, 10), k_block_s);
  a.push(block(0, 0, 420, 10), k_block_s);  // the wrap is not a gap
  EXPECT_EQ(a.lost_samples(), 0u);
  a.push(block(3, 0, 420, 10), 3 * k_block_s);  // blocks 1 and 2 lost
  EXPECT_EQ(a.lost_samples(), 32u);
  EXPECT_DOUBLE_EQ(a.rows()[0].t_s, 5 * 0.032);
  EXPECT_TRUE(std::isnan(a.rows()[6].rpm));  // the window straddles the gap
  EXPECT_FALSE(std::isnan(a.rows()[7].rpm));
}

TEST(LinkStreamBlock, LongSilenceUnwrapsByArrivalTime) {
  StreamAssembler a(8);
  a.push(block(10, 0, 420, 10), 0.0);
  // 9 s without data: 281 blocks, sequence 10 + 281 = 291 = 35 mod 256.
  a.push(block(35, 0, 420, 10), 9.0);
  EXPECT_EQ(a.lost_samples(), 280u * 16u);
  EXPECT_DOUBLE_EQ(a.rows()[0].t_s, 281 * 0.032);
}

TEST(LinkStreamBlock, SaturatedSamplesLeaveRpmUnmeasured) {
  StreamAssembler a(1);
  auto p = block(0, 0, 420, 20);
  p[MCG_STREAM_HEADER + 3] = 255;
  a.push(p, 0.0);
  EXPECT_DOUBLE_EQ(a.rows()[2].rpm, 20 * 60.0 / (2048 * 0.002));
  EXPECT_TRUE(std::isnan(a.rows()[3].rpm));
  EXPECT_DOUBLE_EQ(a.rows()[3].counts, 255.0);
  EXPECT_FALSE(a.push(std::vector<std::uint8_t>(5, 0), 0.0));
}

}  // namespace
}  // namespace mcg::link
