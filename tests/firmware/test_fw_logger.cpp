// The RAM log (255 points at 0x9500), its dump frames, stream blocks, and command playback.
#include <gtest/gtest.h>

#include <cstdlib>
#include <tuple>

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
    EXPECT_EQ(b.set(MCG_REG_B0, 600), MCG_ST_OK);
    EXPECT_EQ(b.set(MCG_REG_B1, -560), MCG_ST_OK);
    EXPECT_EQ(b.write(MCG_REG_DUTY, 350), MCG_ST_OK);
    EXPECT_EQ(b.set(MCG_REG_MODE, MCG_MODE_PI), MCG_ST_OK);
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

// The fields of stream sample k of a block (mcg_protocol.h, "Stream blocks").
struct StreamSample {
  int duty, counts;
  bool clutch, load, cmd;
};
StreamSample sample_at(const Bytes& payload, std::size_t k) {
  const std::size_t at = MCG_STREAM_HEADER + MCG_STREAM_SAMPLE_BYTES * k;
  const unsigned w = static_cast<unsigned>(payload.at(at)) | static_cast<unsigned>(payload.at(at + 1)) << 8 |
                     static_cast<unsigned>(payload.at(at + 2)) << 16;
  const auto sext = [](unsigned v, unsigned bits) {
    const unsigned m = 1u << (bits - 1);
    return static_cast<int>((v & ((1u << bits) - 1)) ^ m) - static_cast<int>(m);
  };
  return {sext(w, 11), sext(w >> 11, 10), (w >> 21 & 1) != 0, (w >> 22 & 1) != 0, (w >> 23 & 1) != 0};
}

std::vector<Frame> stream_blocks(const std::vector<Frame>& frames) {
  std::vector<Frame> out;
  for (const Frame& f : frames) {
    if (f.cmd == MCG_MSG_STREAM) {
      out.push_back(f);
    }
  }
  return out;
}

TEST(FwStream, BlocksEverySixtyFourMillisecondsWithinTheBudget) {
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
    for (const Frame& fr : stream_blocks(frames)) {
      ASSERT_EQ(fr.payload.size(), MCG_STREAM_PAYLOAD);
      if (expect_seq >= 0) {
        ASSERT_EQ(fr.payload[0], expect_seq & 0xFF) << "no block lost";
      }
      expect_seq = fr.payload[0] + 1;
      EXPECT_EQ(fwtest::i16_at(fr.payload, 1), 420);
      for (std::size_t i = 0; i < MCG_STREAM_SAMPLES; ++i) {
        const StreamSample smp = sample_at(fr.payload, i);
        ASSERT_EQ(smp.counts, 28) << "7 pulses/ms over 4 ms";
        ASSERT_EQ(smp.duty, 321);
        ASSERT_FALSE(smp.clutch || smp.load || smp.cmd);
      }
      ++blocks;
    }
  }
  // One block per 64 ms of board time, less the one or two still on the line.
  const auto elapsed_ms = static_cast<int>(host_board_time_ms() - t0);
  EXPECT_GT(elapsed_ms, seconds * 1000);
  EXPECT_NEAR(blocks, elapsed_ms / 64, 2);
  EXPECT_EQ(b.read(MCG_REG_TX_DROPS), 0);
  EXPECT_EQ(reads, seconds * 10);
  // The protocol page's budget: payload and frame bytes per block over the block's time.
  EXPECT_LE((MCG_STREAM_PAYLOAD + MCG_FRAME_OVERHEAD) * 1000.0 / (MCG_STREAM_SAMPLES * MCG_STREAM_PERIOD_MS),
            0.92 * 9600 / 10);
}

// Counts carry the direction of the drive; the outputs of each tick are those that acted during it.
TEST(FwStream, SamplesCarrySignedCountsAndTheOutputs) {
  Board b;
  ASSERT_EQ(b.set(MCG_REG_DUTY_MIN, -1000), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_DUTY, -250), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_CLUTCH, MCG_CLUTCH_ENGAGED), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_LOAD, 1), MCG_ST_OK);
  b.set_pulses(5);
  b.run(10, 5);
  ASSERT_EQ(b.write(MCG_REG_STREAM, 1), MCG_ST_OK);
  const auto blocks = stream_blocks(b.run(200, 5));
  ASSERT_GE(blocks.size(), 2u);
  for (std::size_t k = 0; k < MCG_STREAM_SAMPLES; ++k) {
    const StreamSample s = sample_at(blocks[1].payload, k);
    EXPECT_EQ(s.counts, -20);
    EXPECT_EQ(s.duty, -250);
    EXPECT_TRUE(s.clutch);
    EXPECT_TRUE(s.load);
  }
  // Coasting (duty 0) keeps the direction of the last drive.
  ASSERT_EQ(b.write(MCG_REG_DUTY, 0), MCG_ST_OK);
  const auto later = stream_blocks(b.run(200, 5));
  ASSERT_GE(later.size(), 2u);
  EXPECT_EQ(sample_at(later[1].payload, 0).counts, -20);
  EXPECT_EQ(sample_at(later[1].payload, 0).duty, 0);
}

// Closed loop: each sample's duty is the rounded mean of the PWM over its 4 ticks.
TEST(FwStream, DutyIsTheMeanOverTheSample) {
  Board b;
  ASSERT_EQ(b.set(MCG_REG_COEF_FRAC, 8), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_KP, 64 * 256), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_MODE, MCG_MODE_P), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_STREAM, 1), MCG_ST_OK);
  std::vector<int> duty;
  Bytes all;
  // Pulses that vary from tick to tick, so the P law moves the duty every tick.
  for (int i = 0; i < 400; ++i) {
    host_board_tick(static_cast<std::uint16_t>(i % 9));
    duty.push_back(host_board_duty());
    std::uint8_t buf[512];
    const std::size_t n = host_board_tx(buf, sizeof buf);
    all.insert(all.end(), buf, buf + n);
  }
  fwtest::Decoder dec;
  const auto blocks = stream_blocks(dec.feed(all));
  ASSERT_GE(blocks.size(), 3u);
  // Find where the duty sequence of block 1 lies in the recorded duties.
  std::vector<int> means;
  for (std::size_t k = 0; k < MCG_STREAM_SAMPLES; ++k) {
    means.push_back(sample_at(blocks[1].payload, k).duty);
  }
  bool found = false;
  for (std::size_t start = 0; start + 4 * MCG_STREAM_SAMPLES <= duty.size() && !found; ++start) {
    bool all_match = true;
    bool varies = false;
    for (std::size_t k = 0; k < MCG_STREAM_SAMPLES && all_match; ++k) {
      int sum = 0;
      for (std::size_t j = 0; j < 4; ++j) {
        sum += duty[start + 4 * k + j];
        varies = varies || duty[start + 4 * k + j] != duty[start + 4 * k];
      }
      const int mean = sum >= 0 ? (sum + 2) / 4 : -((2 - sum) / 4);
      all_match = mean == means[k];
    }
    found = all_match && varies;
  }
  EXPECT_TRUE(found) << "no run of 64 ticks whose 4-tick means are the block's duties";
}

// A sequence started while streaming starts on a sample boundary: entries 4k ms apart fall on
// sample boundaries, and the sample of an rpm_cmd change carries the flag.
TEST(FwStream, SequenceStartsOnASampleBoundary) {
  Board b;
  ASSERT_EQ(b.write(MCG_REG_STREAM, 1), MCG_ST_OK);
  b.run(7);
  Bytes entries{0};
  for (const auto& [delay, reg, value] : std::vector<std::tuple<int, int, int>>{
           {0, MCG_REG_CLUTCH, MCG_CLUTCH_ENGAGED}, {40, MCG_REG_RPM_CMD, 500}, {40, MCG_REG_LOAD, 1}}) {
    const Bytes d = fwtest::le16(delay), v = fwtest::le16(value);
    entries.insert(entries.end(), d.begin(), d.end());
    entries.push_back(static_cast<std::uint8_t>(reg));
    entries.insert(entries.end(), v.begin(), v.end());
  }
  ASSERT_EQ(b.request(MCG_CMD_SEQ_WRITE, entries)->payload.at(0), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_SEQ_STATE, MCG_SEQ_PLAY), MCG_ST_OK);
  std::vector<Frame> frames = b.take_other();
  const auto more = b.run(400);
  frames.insert(frames.end(), more.begin(), more.end());
  std::vector<StreamSample> samples;
  for (const Frame& f : stream_blocks(frames)) {
    for (std::size_t k = 0; k < MCG_STREAM_SAMPLES; ++k) {
      samples.push_back(sample_at(f.payload, k));
    }
  }
  std::size_t clutch_at = samples.size();
  for (std::size_t k = 0; k < samples.size(); ++k) {
    if (samples[k].clutch && clutch_at == samples.size()) {
      clutch_at = k;
    }
  }
  ASSERT_LT(clutch_at + 20, samples.size());
  EXPECT_TRUE(samples[clutch_at + 10].cmd) << "40 ms = 10 samples later";
  EXPECT_FALSE(samples[clutch_at + 9].cmd || samples[clutch_at + 11].cmd);
  EXPECT_FALSE(samples[clutch_at + 19].load);
  EXPECT_TRUE(samples[clutch_at + 20].load);
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
  // 200001 ticks between the two reads: 3125 blocks, one more depending on the phase.
  EXPECT_LE(std::abs((seq_after - seq_before + 256) % 256 - 3125 % 256), 1)
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
  entry(0, MCG_REG_CLUTCH, MCG_CLUTCH_ENGAGED);
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

// The log signs the direction-less pulses with the drive, as the stream does.
TEST(FwLogger, PointsCarryTheDriveDirection) {
  Board b;
  ASSERT_EQ(b.set(MCG_REG_DUTY_MIN, -1000), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_DUTY, -300), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_LOG_INTERVAL, 4), MCG_ST_OK);
  b.set_pulses(5);
  b.run(10, 5);
  ASSERT_EQ(b.request(MCG_CMD_LOG_START)->payload.at(0), MCG_ST_OK);
  b.run(4 * static_cast<int>(MCG_LOG_POINTS) + 10, 5);
  for (std::size_t k = 0; k < MCG_LOG_POINTS; ++k) {
    ASSERT_EQ(static_cast<std::int16_t>(host_board_log()[k]), -20) << k;
  }
}
