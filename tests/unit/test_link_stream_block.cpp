// Unit tests of stream block assembly (protocol 2): sample decoding, the row convention, the
// rpm window, rpm_cmd changes, loss counting.
#include "link/stream_block.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "mcg_protocol.h"

namespace mcg::link {
namespace {

struct Sample {
  int duty = 0;
  int counts = 0;
  bool clutch = false;
  bool load = false;
  bool cmd = false;
};

/// Packs a sample as the firmware does (mcg_protocol.h, "Stream blocks").
void put(std::vector<std::uint8_t>& p, const Sample& s) {
  const auto d = static_cast<unsigned>(s.duty) & 0x7FFu;
  const auto c = static_cast<unsigned>(s.counts) & 0x3FFu;
  const unsigned w = d | c << 11 | (s.clutch ? 1u << 21 : 0u) | (s.load ? 1u << 22 : 0u) | (s.cmd ? 1u << 23 : 0u);
  p.push_back(static_cast<std::uint8_t>(w & 0xFF));
  p.push_back(static_cast<std::uint8_t>((w >> 8) & 0xFF));
  p.push_back(static_cast<std::uint8_t>(w >> 16));
}

std::vector<std::uint8_t> block(std::uint8_t seq, std::int16_t rpm_cmd, const std::vector<Sample>& samples) {
  std::vector<std::uint8_t> p{seq};
  p.push_back(static_cast<std::uint8_t>(rpm_cmd & 0xFF));
  p.push_back(static_cast<std::uint8_t>(rpm_cmd >> 8));
  for (std::size_t k = 0; k < MCG_STREAM_SAMPLES; ++k) put(p, samples.size() == 1 ? samples[0] : samples.at(k));
  return p;
}

std::vector<std::uint8_t> steady(std::uint8_t seq, int duty, int counts) {
  return block(seq, 420, {Sample{duty, counts, true, false, false}});
}

constexpr double k_block_s = 0.064;

TEST(LinkStreamBlock, DecodesEverySampleField) {
  std::vector<std::uint8_t> p;
  put(p, {-1000, -511, true, false, true});
  const StreamSample s = decode_stream_sample(std::span<const std::uint8_t, 3>(p.data(), 3));
  EXPECT_EQ(s.duty_permille, -1000);
  EXPECT_EQ(s.counts, -511);
  EXPECT_TRUE(s.clutch_engaged);
  EXPECT_FALSE(s.load_closed);
  EXPECT_TRUE(s.rpm_cmd_written);
  p.clear();
  put(p, {1000, 300, false, true, false});
  const StreamSample t = decode_stream_sample(std::span<const std::uint8_t, 3>(p.data(), 3));
  EXPECT_EQ(t.duty_permille, 1000);
  EXPECT_EQ(t.counts, 300);
  EXPECT_FALSE(t.clutch_engaged);
  EXPECT_TRUE(t.load_closed);
  EXPECT_FALSE(t.rpm_cmd_written);
}

TEST(LinkStreamBlock, RowsFollowTheDataContract) {
  StreamAssembler a(4);  // 16 ms window, as the board's own rpm register
  ASSERT_TRUE(a.push(steady(7, 355, 30), 0.0));
  const auto& rows = a.rows();
  ASSERT_EQ(rows.size(), 16u);
  for (std::size_t k = 0; k < 16; ++k) EXPECT_DOUBLE_EQ(rows[k].t_s, 0.004 * static_cast<double>(k));
  // Row n: duty of [t, t + 4 ms), counts of (t - 4 ms, t]: row 0 has no counts yet.
  EXPECT_TRUE(std::isnan(rows[0].counts));
  EXPECT_DOUBLE_EQ(rows[1].counts, 30.0);
  EXPECT_DOUBLE_EQ(rows[0].duty, 0.355);
  EXPECT_EQ(rows[0].clutch, 2.0);
  EXPECT_EQ(rows[0].load, 0.0);
  EXPECT_TRUE(std::isnan(rows[3].rpm));  // 3 samples measured: the window is not full yet
  // 4 samples of 30 pulses in 16 ms: 120 * 1875 / 1024 rpm (the protocol's exact factor).
  EXPECT_DOUBLE_EQ(rows[4].rpm, 120.0 * 1875.0 / 1024.0);
  EXPECT_DOUBLE_EQ(rows[15].rpm_cmd, 420.0);
  ASSERT_TRUE(a.push(steady(8, -20, -31), k_block_s));
  EXPECT_DOUBLE_EQ(a.rows()[0].t_s, 0.064);
  EXPECT_DOUBLE_EQ(a.rows()[0].counts, 30.0);  // the last sample of the block before
  EXPECT_DOUBLE_EQ(a.rows()[1].counts, -31.0);
  EXPECT_DOUBLE_EQ(a.rows()[0].duty, -0.02);
  EXPECT_DOUBLE_EQ(a.rows()[2].rpm, (2 * 30 - 2 * 31) * 1875.0 / 1024.0);
  EXPECT_EQ(a.lost_samples(), 0u);
}

TEST(LinkStreamBlock, RpmCmdChangesAtTheFlaggedSample) {
  StreamAssembler a(4);
  a.push(block(0, 420, {Sample{}}), 0.0);
  std::vector<Sample> s(16);
  s[5].cmd = true;
  a.push(block(1, 500, s), k_block_s);
  EXPECT_DOUBLE_EQ(a.rows()[4].rpm_cmd, 420.0);
  EXPECT_DOUBLE_EQ(a.rows()[5].rpm_cmd, 500.0);
  s[9].cmd = true;
  a.push(block(2, 300, s), k_block_s);
  EXPECT_DOUBLE_EQ(a.rows()[4].rpm_cmd, 500.0);
  EXPECT_TRUE(std::isnan(a.rows()[5].rpm_cmd)) << "two changes in a block: the one between is not reported";
  EXPECT_DOUBLE_EQ(a.rows()[9].rpm_cmd, 300.0);
}

TEST(LinkStreamBlock, SequenceGapsAreLostSamplesAndTimeSkips) {
  StreamAssembler a(4);
  a.push(steady(254, 0, 10), 0.0);
  a.push(steady(255, 0, 10), k_block_s);
  a.push(steady(0, 0, 10), k_block_s);  // the wrap is not a gap
  EXPECT_EQ(a.lost_samples(), 0u);
  a.push(steady(3, 0, 10), 3 * k_block_s);  // blocks 1 and 2 lost
  EXPECT_EQ(a.lost_samples(), 32u);
  // A row per lost sample, unmeasured, then the block's own rows.
  ASSERT_EQ(a.rows().size(), 48u);
  EXPECT_DOUBLE_EQ(a.rows()[0].t_s, 3 * 0.064);
  EXPECT_TRUE(std::isnan(a.rows()[0].duty) && std::isnan(a.rows()[0].clutch) && std::isnan(a.rows()[0].rpm_cmd));
  EXPECT_TRUE(std::isnan(a.rows()[31].load));
  const StreamRow* rows = a.rows().data() + 32;
  EXPECT_DOUBLE_EQ(rows[0].t_s, 5 * 0.064);
  EXPECT_DOUBLE_EQ(rows[0].duty, 0.0);
  EXPECT_TRUE(std::isnan(rows[0].counts));  // nothing carries across the gap
  EXPECT_TRUE(std::isnan(rows[3].rpm));
  EXPECT_FALSE(std::isnan(rows[4].rpm));  // the window holds the block's first 4 samples
}

TEST(LinkStreamBlock, LongSilenceUnwrapsByArrivalTimeIntoABreak) {
  StreamAssembler a(4);
  a.push(steady(10, 0, 10), 0.0);
  // 18 s without data: 281 blocks, sequence 10 + 281 = 291 = 35 mod 256. Past the sequence
  // number's range the gap is one break row, not 4480 rows of NaN.
  a.push(steady(35, 0, 10), 18.0);
  EXPECT_EQ(a.lost_samples(), 280u * 16u);
  EXPECT_EQ(a.breaks(), 1u);
  ASSERT_EQ(a.rows().size(), 17u);
  EXPECT_DOUBLE_EQ(a.rows()[0].t_s, 16 * 0.004);  // the first missing sample
  EXPECT_TRUE(std::isnan(a.rows()[0].duty) && std::isnan(a.rows()[0].rpm) && std::isnan(a.rows()[0].counts));
  EXPECT_DOUBLE_EQ(a.rows()[1].t_s, 281 * 0.064);
}

TEST(LinkStreamBlock, ADayBetweenBlocksIsOneBreakRow) {
  StreamAssembler a(4);
  a.push(steady(0, 0, 10), 0.0);
  a.push(steady(1, 0, 10), k_block_s);
  a.push(steady(77, 0, 10), 86400.0);  // a laptop suspended for a day
  ASSERT_EQ(a.rows().size(), 17u);
  EXPECT_EQ(a.breaks(), 1u);
  EXPECT_TRUE(std::isnan(a.rows()[0].duty));
  EXPECT_NEAR(a.rows()[1].t_s, 86400.0 + k_block_s, 0.064 * 128);
  EXPECT_DOUBLE_EQ(std::fmod(std::round(a.rows()[1].t_s / 0.004), 256.0 * 16.0), (77.0 - 0.0) * 16.0)
      << "the block keeps its sequence number's place";
  a.push(steady(78, 0, 10), k_block_s);
  EXPECT_EQ(a.rows().size(), 16u) << "after the break, rows as usual";
}

TEST(LinkStreamBlock, ARestartIsABreakPlacedByTheSilence) {
  StreamAssembler a(4);
  a.push(steady(200, 0, 10), 0.0);
  a.restart();  // the port came back; the board restarted its sequence numbers at 0
  a.push(steady(0, 0, 10), 2.0);
  EXPECT_EQ(a.breaks(), 1u);
  ASSERT_EQ(a.rows().size(), 17u);
  EXPECT_DOUBLE_EQ(a.rows()[0].t_s, 16 * 0.004);
  EXPECT_NEAR(a.rows()[1].t_s, 2.0, 0.064);
  a.push(steady(1, 0, 10), k_block_s);
  EXPECT_EQ(a.rows().size(), 16u);
  EXPECT_EQ(a.breaks(), 1u);
}

TEST(LinkStreamBlock, SaturatedSamplesLeaveRpmUnmeasured) {
  StreamAssembler a(1);
  std::vector<Sample> s(16, Sample{0, 20});
  s[3].counts = MCG_STREAM_COUNTS_MAX;
  a.push(block(0, 420, s), 0.0);
  EXPECT_DOUBLE_EQ(a.rows()[3].rpm, 20 * 60.0 / (2048 * 0.004));
  EXPECT_TRUE(std::isnan(a.rows()[4].rpm));
  EXPECT_TRUE(std::isnan(a.rows()[4].counts));
  EXPECT_FALSE(a.push(std::vector<std::uint8_t>(5, 0), 0.0));
}

}  // namespace
}  // namespace mcg::link
