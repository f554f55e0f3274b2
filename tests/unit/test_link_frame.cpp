// Unit tests of the frame codec: CRC, layout, resynchronisation after noise, loss and silence.
#include "link/frame.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string_view>

namespace mcg::link {
namespace {

using Bytes = std::vector<std::uint8_t>;

std::vector<Frame> decode_all(Decoder& d, const Bytes& bytes, double t_s = 0.0) {
  std::vector<Frame> out;
  d.feed(bytes, t_s, out);
  return out;
}

TEST(LinkFrame, CrcIsCcittFalse) {
  const std::string_view check = "123456789";
  const Bytes bytes(check.begin(), check.end());
  EXPECT_EQ(crc16(bytes), 0x29B1);  // the catalogued check value of CRC-16/CCITT-FALSE
  EXPECT_EQ(crc16({}), 0xFFFF);
}

TEST(LinkFrame, EncodeLayout) {
  const Bytes payload{0x13};
  const Bytes wire = encode(0x02, payload);
  ASSERT_EQ(wire.size(), 6u);
  EXPECT_EQ(wire[0], 0xA5);
  EXPECT_EQ(wire[1], 1);
  EXPECT_EQ(wire[2], 0x02);
  EXPECT_EQ(wire[3], 0x13);
  const std::uint16_t crc = crc16(Bytes{1, 0x02, 0x13});
  EXPECT_EQ(wire[4], crc & 0xFF);
  EXPECT_EQ(wire[5], crc >> 8);
}

TEST(LinkFrame, ByteByByteRoundTrip) {
  Decoder d;
  const Bytes payload{0xA5, 0x00, 0xFF, 0x5A, 0xA5};  // SYNC bytes inside the payload
  const Bytes wire = encode(0xF0, payload);
  std::vector<Frame> out;
  for (std::size_t i = 0; i < wire.size(); ++i) d.feed(Bytes{wire[i]}, static_cast<double>(i) * 1e-3, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].cmd, 0xF0);
  EXPECT_EQ(out[0].payload, payload);
  EXPECT_FALSE(d.pending());
}

TEST(LinkFrame, NoiseBeforeAFrameIsSkipped) {
  Decoder d;
  Bytes wire{0x00, 0x13, 0xA5};  // a stray SYNC with an impossible length after it
  wire.push_back(0xF7);
  const Bytes good = encode(0x81, Bytes{0, 1, 2});
  wire.insert(wire.end(), good.begin(), good.end());
  const auto frames = decode_all(d, wire);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].cmd, 0x81);
  EXPECT_EQ(d.stats().too_long, 1u);
  EXPECT_EQ(d.stats().skipped_bytes, 3u);  // 00 13 and the 0xF7 after the dropped SYNC
}

TEST(LinkFrame, CorruptedFrameIsDroppedAndTheNextOneFound) {
  Decoder d;
  Bytes bad = encode(0x82, Bytes{0, 0x13, 0x34, 0x12});
  bad[4] ^= 0x10;
  const Bytes good = encode(0x83, Bytes{0, 0x02, 0x20, 0x00});
  Bytes wire = bad;
  wire.insert(wire.end(), good.begin(), good.end());
  const auto frames = decode_all(d, wire);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].cmd, 0x83);
  EXPECT_EQ(d.stats().bad_crc, 1u);
}

TEST(LinkFrame, FrameStartingInsideATruncatedOneIsFound) {
  // The first frame lost its last three bytes: its LEN reaches into the second frame, whose
  // SYNC must be found again after the first candidate fails its CRC.
  Decoder d;
  Bytes first = encode(0xF0, Bytes(21, 0x11));
  first.resize(first.size() - 3);
  const Bytes second = encode(0x82, Bytes{0, 0x13, 0xA4, 0x01});
  Bytes wire = first;
  wire.insert(wire.end(), second.begin(), second.end());
  const auto frames = decode_all(d, wire);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].cmd, 0x82);
  EXPECT_EQ(frames[0].payload, (Bytes{0, 0x13, 0xA4, 0x01}));
}

TEST(LinkFrame, SilenceInsideAFrameDropsIt) {
  Decoder d(0.02);
  std::vector<Frame> out;
  const Bytes partial = encode(0x81, Bytes{0, 1, 0, 1, 0, 2})  ;
  d.feed(Bytes(partial.begin(), partial.begin() + 4), 0.000, out);
  EXPECT_TRUE(d.pending());
  d.poll(0.015, out);
  EXPECT_TRUE(d.pending());  // 15 ms: still waiting
  d.poll(0.025, out);
  EXPECT_FALSE(d.pending());
  EXPECT_EQ(d.stats().timeouts, 1u);
  d.feed(encode(0x84, Bytes{0}), 0.030, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].cmd, 0x84);
}

TEST(LinkFrame, LateReadIsNotASilence) {
  // The host was busy for 200 ms; the rest of the frame waited in the port's buffer. Only a
  // wait that brought nothing (poll) counts as a silence on the line.
  Decoder d(0.02);
  std::vector<Frame> out;
  const Bytes wire = encode(0x81, Bytes{0, 1, 0, 1, 0, 2});
  d.feed(Bytes(wire.begin(), wire.begin() + 4), 0.000, out);
  d.feed(Bytes(wire.begin() + 4, wire.end()), 0.200, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(d.stats().timeouts, 0u);
}

TEST(LinkFrame, EveryIntactFrameSurvivesRandomDamage) {
  std::mt19937_64 rng(20240611);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<int> len(0, 30);
  std::vector<Frame> sent;
  std::vector<bool> intact;
  Bytes wire;
  for (int i = 0; i < 2000; ++i) {
    Frame f;
    f.cmd = static_cast<std::uint8_t>(byte(rng));
    f.payload.resize(static_cast<std::size_t>(len(rng)));
    for (auto& b : f.payload) b = static_cast<std::uint8_t>(byte(rng));
    Bytes bytes = encode(f.cmd, f.payload);
    const int fate = byte(rng) % 10;
    if (fate == 0) bytes[static_cast<std::size_t>(byte(rng)) % bytes.size()] ^= static_cast<std::uint8_t>(1 + byte(rng) % 255);
    if (fate == 1) bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(byte(rng)) % bytes.size()));
    if (fate == 2) bytes.insert(bytes.begin() + 1, static_cast<std::uint8_t>(byte(rng)));
    wire.insert(wire.end(), bytes.begin(), bytes.end());
    sent.push_back(f);
    intact.push_back(fate > 2);
  }
  Decoder d;
  std::vector<Frame> got;
  for (std::size_t at = 0; at < wire.size(); at += 7) {
    d.feed(Bytes(wire.begin() + static_cast<std::ptrdiff_t>(at),
                 wire.begin() + static_cast<std::ptrdiff_t>(std::min(at + 7, wire.size()))),
           0.0, got);
  }
  // Every intact frame arrives, in order; nothing arrives that was not sent.
  std::size_t g = 0;
  std::size_t intact_count = 0;
  for (std::size_t i = 0; i < sent.size(); ++i) {
    if (g < got.size() && got[g].cmd == sent[i].cmd && got[g].payload == sent[i].payload) {
      ++g;
      continue;
    }
    EXPECT_FALSE(intact[i]) << "intact frame " << i << " lost";
  }
  for (std::size_t i = 0; i < sent.size(); ++i) intact_count += intact[i] ? 1u : 0u;
  EXPECT_EQ(g, got.size()) << "a frame arrived that was never sent";
  EXPECT_GE(g, intact_count);
  EXPECT_GT(d.stats().bad_crc + d.stats().too_long, 100u);
}

}  // namespace
}  // namespace mcg::link
