// The RAM log (255 points at 0x9500), its dump frames, stream blocks, and command playback.
#include <gtest/gtest.h>

#include <cstdlib>

#include "fw_harness.hpp"

using fwtest::Board;
using fwtest::Bytes;
using fwtest::Frame;

namespace {

// Pulses of tick n: varied, so that each point's sum shows which ticks it covered.
std::uint16_t pattern(long n) { return static_cast<std::uint16_t>(5 + (n * 7) % 11); }

}  // namespace

TEST(FwLogger, RecordsPointsAtTheInterval) {
  for (int interval : {1, 4, 37, 255}) {
    SCOPED_TRACE(interval);
    Board b;
    ASSERT_EQ(b.write(MCG_REG_LOG_INTERVAL, interval), MCG_ST_OK);
    ASSERT_EQ(b.request(MCG_CMD_LOG_START)->payload.at(0), MCG_ST_OK);
    // The first tick after the start is tick 1 of point 0.
    const long total = 255L * interval;
    for (long n = 1; n <= total; ++n) {
      host_board_tick(pattern(n));
      if (n == total - 1) {
        ASSERT_EQ(g_log_count, 254) << "one tick before the end";
        ASSERT_TRUE(g_log_running);
      }
    }
    EXPECT_EQ(g_log_count, MCG_LOG_POINTS);
    EXPECT_FALSE(g_log_running);
    const std::uint16_t* log = host_board_log();
    for (int k = 0; k < 255; ++k) {
      long expect = 0;
      for (long n = 1L + k * interval; n <= (k + 1L) * interval; ++n) {
        expect += pattern(n);
      }
      ASSERT_EQ(log[k], expect) << "point " << k;
    }
    host_board_tick(9);
    EXPECT_EQ(g_log_count, MCG_LOG_POINTS) << "stops after 255 points";
    EXPECT_EQ(b.read(MCG_REG_FLAGS) & static_cast<int>(MCG_FLAG_LOG_FULL),
              static_cast<int>(MCG_FLAG_LOG_FULL));
  }
}

// A main loop held up for several ticks (an LCD refresh on the board) runs the missed ticks late:
// the log keeps its time base and loses no pulse.
TEST(FwLogger, LateTicksKeepTimeAndPulses) {
  Board b;
  ASSERT_EQ(b.write(MCG_REG_LOG_INTERVAL, 3), MCG_ST_OK);
  ASSERT_EQ(b.request(MCG_CMD_LOG_START)->payload.at(0), MCG_ST_OK);
  long total = 0;
  for (int n = 1; n <= 765; ++n) {
    const auto p = pattern(n);
    total += p;
    if (n % 7 != 0 && n != 765) {
      host_board_stall(p);  // six ticks in seven come late
    } else {
      host_board_tick(p);
    }
  }
  EXPECT_EQ(g_log_count, MCG_LOG_POINTS);
  long logged = 0;
  for (int k = 0; k < 255; ++k) {
    logged += host_board_log()[k];
  }
  EXPECT_EQ(logged, total) << "every pulse counted once";
  EXPECT_EQ(host_board_time_ms(), 765u + 2u);  // + the ticks of the two requests
}

TEST(FwLogger, IntervalLockedWhileRecording) {
  Board b;
  ASSERT_EQ(b.request(MCG_CMD_LOG_START)->payload.at(0), MCG_ST_OK);
  EXPECT_EQ(b.write(MCG_REG_LOG_INTERVAL, 9), MCG_ST_BUSY);
  EXPECT_EQ(b.read(MCG_REG_LOG_INTERVAL), 4);
  EXPECT_EQ(b.request(MCG_CMD_LOG_DUMP)->payload, Bytes{MCG_ST_BUSY});
}

TEST(FwLogger, DumpSendsEveryPointInChunks) {
  Board b;
  ASSERT_EQ(b.write(MCG_REG_LOG_INTERVAL, 2), MCG_ST_OK);
  ASSERT_EQ(b.request(MCG_CMD_LOG_START)->payload.at(0), MCG_ST_OK);
  for (long n = 1; n <= 510; ++n) {
    host_board_tick(pattern(n));
  }
  b.set_baud(9600);
  const auto reply = b.request(MCG_CMD_LOG_DUMP);
  ASSERT_TRUE(reply);
  EXPECT_EQ(reply->payload, (Bytes{MCG_ST_OK, 255, 2}));
  std::vector<Frame> frames = b.take_other();
  const auto rest = b.run(1500);
  frames.insert(frames.end(), rest.begin(), rest.end());
  std::vector<int> points;
  int chunks = 0;
  for (const Frame& f : frames) {
    if (f.cmd != MCG_MSG_LOG_DATA) {
      continue;
    }
    ASSERT_EQ(f.payload.at(0), points.size()) << "chunks in order, none missing";
    const std::size_t n = f.payload.at(1);
    ASSERT_EQ(f.payload.size(), MCG_LOGDATA_HEADER + 2 * n);
    for (std::size_t i = 0; i < n; ++i) {
      points.push_back(fwtest::i16_at(f.payload, MCG_LOGDATA_HEADER + 2 * i));
    }
    ++chunks;
  }
  EXPECT_EQ(chunks, static_cast<int>(MCG_LOG_DUMP_FRAMES));
  ASSERT_EQ(points.size(), MCG_LOG_POINTS);
  for (int k = 0; k < 255; ++k) {
    EXPECT_EQ(points[static_cast<std::size_t>(k)], pattern(2 * k + 1) + pattern(2 * k + 2));
  }
}

// Report bug: "trying to record data into ram will crash the system ... the closed loop flag set
// when recording into ram". Recording changes neither the mode nor the control: the duty sequence
// of a PI run is the same with and without a recording.
TEST(FwLogger, RegressionRecordingLeavesControlAlone) {
  auto run = [](bool record) {
    Board b;
    b.set_pulses(13);
    EXPECT_EQ(b.write(MCG_REG_B0, 600), MCG_ST_OK);
    EXPECT_EQ(b.write(MCG_REG_B1, -560), MCG_ST_OK);
    EXPECT_EQ(b.write(MCG_REG_DUTY, 350), MCG_ST_OK);
    EXPECT_EQ(b.write(MCG_REG_MODE, MCG_MODE_PI), MCG_ST_OK);
    if (record) {
      EXPECT_EQ(b.request(MCG_CMD_LOG_START)->payload.at(0), MCG_ST_OK);
    } else {
      EXPECT_EQ(b.request(MCG_CMD_VERSION)->payload.at(0), MCG_ST_OK);
    }
    std::vector<int> duty;
    for (long n = 0; n < 1100; ++n) {
      host_board_tick(pattern(n));
      duty.push_back(host_board_duty());
    }
    EXPECT_EQ(b.read(MCG_REG_MODE), static_cast<int>(MCG_MODE_PI));
    EXPECT_EQ(g_log_count, record ? 255 : 0);
    return duty;
  };
  EXPECT_EQ(run(true), run(false));

  // And in open loop the recording does not switch anything on.
  Board b;
  ASSERT_EQ(b.write(MCG_REG_DUTY, 275), MCG_ST_OK);
  ASSERT_EQ(b.request(MCG_CMD_LOG_START)->payload.at(0), MCG_ST_OK);
  b.run(1100, 12);
  EXPECT_EQ(b.read(MCG_REG_MODE), static_cast<int>(MCG_MODE_OPEN));
  EXPECT_EQ(host_board_duty(), 275);
  EXPECT_EQ(host_board_log()[100], 48);
}

TEST(FwStream, BlocksEveryThirtyTwoMillisecondsWithinTheBudget) {
  Board b;
  b.set_baud(9600);
  b.set_pulses(7);
  ASSERT_EQ(b.write(MCG_REG_DUTY, 321), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_STREAM, 1), MCG_ST_OK);
  const int seconds = 10;
  const std::uint32_t t0 = host_board_time_ms();
  int blocks = 0;
  int expect_seq = -1;
  int reads = 0;
  for (int s = 0; s < seconds * 10; ++s) {
    // 10 register reads a second on top of the stream.
    const auto f = b.request(MCG_CMD_READ, {MCG_REG_RPM});
    ASSERT_TRUE(f);
    ++reads;
    std::vector<Frame> frames = b.take_other();
    const auto more = b.run(90, 7);
    frames.insert(frames.end(), more.begin(), more.end());
    for (const Frame& fr : frames) {
      if (fr.cmd != MCG_MSG_STREAM) {
        continue;
      }
      ASSERT_EQ(fr.payload.size(), MCG_STREAM_HEADER + MCG_STREAM_SAMPLES);
      if (expect_seq >= 0) {
        ASSERT_EQ(fr.payload[0], expect_seq & 0xFF) << "no block lost";
      }
      expect_seq = fr.payload[0] + 1;
      EXPECT_EQ(fwtest::i16_at(fr.payload, 1), 321);
      EXPECT_EQ(fwtest::i16_at(fr.payload, 3), 420);
      for (std::size_t i = 0; i < MCG_STREAM_SAMPLES; ++i) {
        ASSERT_EQ(fr.payload[MCG_STREAM_HEADER + i], 14) << "7 pulses/ms over 2 ms";
      }
      ++blocks;
    }
  }
  // One block per 32 ms of board time, less the one or two still on the line.
  const auto elapsed_ms = static_cast<int>(host_board_time_ms() - t0);
  EXPECT_GT(elapsed_ms, seconds * 1000);
  EXPECT_NEAR(blocks, elapsed_ms / 32, 2);
  EXPECT_EQ(b.read(MCG_REG_TX_DROPS), 0);
  EXPECT_EQ(reads, seconds * 10);
}

// A log dump while the stream runs at 9600 baud: the dump takes the spare bytes, no block is lost.
TEST(FwStream, DumpDuringStreamLosesNothing)
{
  Board b;
  b.set_baud(9600);
  b.set_pulses(5);
  ASSERT_EQ(b.write(MCG_REG_LOG_INTERVAL, 1), MCG_ST_OK);
  ASSERT_EQ(b.request(MCG_CMD_LOG_START)->payload.at(0), MCG_ST_OK);
  b.run(300, 5);
  ASSERT_EQ(b.write(MCG_REG_STREAM, 1), MCG_ST_OK);
  b.run(100, 5);
  ASSERT_TRUE(b.request(MCG_CMD_LOG_DUMP));
  std::vector<Frame> frames = b.take_other();
  const auto rest = b.run(8000, 5);
  frames.insert(frames.end(), rest.begin(), rest.end());
  int chunks = 0;
  int last_seq = -1;
  int gaps = 0;
  for (const Frame& f : frames) {
    if (f.cmd == MCG_MSG_LOG_DATA) {
      ++chunks;
    } else if (f.cmd == MCG_MSG_STREAM) {
      if (last_seq >= 0 && f.payload[0] != ((last_seq + 1) & 0xFF)) {
        ++gaps;
      }
      last_seq = f.payload[0];
    }
  }
  EXPECT_EQ(chunks, static_cast<int>(MCG_LOG_DUMP_FRAMES));
  EXPECT_EQ(gaps, 0);
  EXPECT_EQ(b.read(MCG_REG_TX_DROPS), 0);
}

TEST(FwStream, LostBlocksShowAsSequenceGaps) {
  Board b;
  ASSERT_EQ(b.write(MCG_REG_STREAM, 1), MCG_ST_OK);
  b.run(64);
  const int seq_before = b.read(MCG_REG_STREAM_SEQ);
  // The host stops reading: the line buffer fills, then the board drops whole blocks.
  for (int n = 0; n < 200000; ++n) {
    host_board_tick(3);
  }
  const int drops = b.read(MCG_REG_TX_DROPS);
  EXPECT_GT(drops, 0);
  const int seq_after = b.read(MCG_REG_STREAM_SEQ);
  // 200001 ticks between the two reads: 6250 blocks, one more depending on the phase.
  EXPECT_LE(std::abs((seq_after - seq_before + 256) % 256 - 6250 % 256), 1)
      << "the sequence advances for dropped blocks too";
}

TEST(FwSequence, PlaysEntriesAtTheirTimes) {
  Board b;
  Bytes entries{0};  // index 0
  auto entry = [&](int delay, std::uint8_t reg, int value) {
    const Bytes d = fwtest::le16(delay), v = fwtest::le16(value);
    entries.insert(entries.end(), d.begin(), d.end());
    entries.push_back(reg);
    entries.insert(entries.end(), v.begin(), v.end());
  };
  entry(5, MCG_REG_DUTY, 100);
  entry(10, MCG_REG_DUTY, 200);
  entry(0, MCG_REG_CLUTCH, 1);
  entry(3, MCG_REG_LOAD, 1);
  const auto w = b.request(MCG_CMD_SEQ_WRITE, entries);
  ASSERT_TRUE(w);
  EXPECT_EQ(w->payload, (Bytes{MCG_ST_OK, 4}));
  EXPECT_EQ(b.read(MCG_REG_SEQ_LEN), 4);
  ASSERT_EQ(b.write(MCG_REG_SEQ_STATE, MCG_SEQ_PLAY), MCG_ST_OK);
  std::vector<int> duty, clutch, load;
  for (int t = 1; t <= 25; ++t) {
    host_board_tick(0);
    duty.push_back(host_board_duty());
    clutch.push_back(host_board_clutch());
    load.push_back(host_board_load());
  }
  // Entry k is written on tick 1 + delay_0 + ... + delay_k (index = tick - 1); outputs switch at
  // once, a duty reaches the PWM with the next control update (the update runs first in a tick).
  EXPECT_EQ(duty[5], 0);
  EXPECT_EQ(duty[6], 100);  // written on tick 6
  EXPECT_EQ(duty[15], 100);
  EXPECT_EQ(duty[16], 200);  // written on tick 16
  EXPECT_EQ(clutch[14], 0);
  EXPECT_EQ(clutch[15], 1);  // tick 16
  EXPECT_EQ(load[17], 0);
  EXPECT_EQ(load[18], 1);  // tick 19
  EXPECT_EQ(b.read(MCG_REG_SEQ_STATE), static_cast<int>(MCG_SEQ_STOP));
}

TEST(FwSequence, LoopsAndRefusesChangesWhilePlaying) {
  Board b;
  Bytes entries{0};
  for (int v : {100, 300}) {
    const Bytes d = fwtest::le16(4), val = fwtest::le16(v);
    entries.insert(entries.end(), d.begin(), d.end());
    entries.push_back(MCG_REG_DUTY);
    entries.insert(entries.end(), val.begin(), val.end());
  }
  ASSERT_EQ(b.request(MCG_CMD_SEQ_WRITE, entries)->payload.at(0), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_SEQ_STATE, MCG_SEQ_LOOP), MCG_ST_OK);
  EXPECT_EQ(b.request(MCG_CMD_SEQ_WRITE, entries)->payload, Bytes{MCG_ST_BUSY});
  EXPECT_EQ(b.request(MCG_CMD_SEQ_CLEAR)->payload, Bytes{MCG_ST_BUSY});
  // Period 1 + 4 + 4 = 9 ms: count the changes of duty over 900 ms.
  int changes = 0;
  int last = host_board_duty();
  for (int t = 0; t < 900; ++t) {
    host_board_tick(0);
    changes += host_board_duty() != last;
    last = host_board_duty();
  }
  EXPECT_NEAR(changes, 200, 2);
  ASSERT_EQ(b.write(MCG_REG_SEQ_STATE, MCG_SEQ_STOP), MCG_ST_OK);
  EXPECT_EQ(b.request(MCG_CMD_SEQ_CLEAR)->payload, Bytes{MCG_ST_OK});
  EXPECT_EQ(b.write(MCG_REG_SEQ_STATE, MCG_SEQ_PLAY), MCG_ST_RANGE) << "nothing to play";
}

TEST(FwSequence, ChecksEntriesWhenStored) {
  Board b;
  auto one = [](std::uint8_t index, std::uint8_t reg) { return Bytes{index, 1, 0, reg, 0, 0}; };
  EXPECT_EQ(b.request(MCG_CMD_SEQ_WRITE, one(0, MCG_REG_RPM))->payload, Bytes{MCG_ST_READ_ONLY});
  EXPECT_EQ(b.request(MCG_CMD_SEQ_WRITE, one(0, MCG_REG_SEQ_STATE))->payload, Bytes{MCG_ST_READ_ONLY});
  EXPECT_EQ(b.request(MCG_CMD_SEQ_WRITE, one(0, 0x7E))->payload, Bytes{MCG_ST_BAD_REG});
  EXPECT_EQ(b.request(MCG_CMD_SEQ_WRITE, one(1, MCG_REG_DUTY))->payload, Bytes{MCG_ST_RANGE}) << "no holes";
  EXPECT_EQ(b.request(MCG_CMD_SEQ_WRITE, Bytes{0, 1, 2})->payload, Bytes{MCG_ST_BAD_LENGTH});
  EXPECT_EQ(b.read(MCG_REG_SEQ_LEN), 0);
}
