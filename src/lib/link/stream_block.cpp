// Stream block assembly.
#include "link/stream_block.hpp"

#include <algorithm>
#include <array>
#include "common/demand.hpp"
#include <cmath>
#include <limits>

#include "link/frame.hpp"  // get_i16
#include "mcg_protocol.h"  // MCG_STREAM_*

namespace mcg::link {

namespace {

constexpr double k_sample_s = MCG_STREAM_PERIOD_MS * 1e-3;
constexpr double k_block_s = k_sample_s * MCG_STREAM_SAMPLES;
constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

/// Sign-extends the low `bits` bits of `v`.
int sign_extend(unsigned v, unsigned bits) {
  const unsigned m = 1u << (bits - 1u);
  const unsigned x = v & ((1u << bits) - 1u);
  return static_cast<int>(x ^ m) - static_cast<int>(m);
}

}  // namespace

StreamSample decode_stream_sample(std::span<const std::uint8_t, 3> b) {
  const unsigned w = static_cast<unsigned>(b[0]) | static_cast<unsigned>(b[1]) << 8 | static_cast<unsigned>(b[2]) << 16;
  return {sign_extend(w, 11), sign_extend(w >> 11, 10), (b[2] & MCG_STREAM_BIT_CLUTCH) != 0,
          (b[2] & MCG_STREAM_BIT_LOAD) != 0, (b[2] & MCG_STREAM_BIT_CMD) != 0};
}

StreamAssembler::StreamAssembler(int window_samples)
    : m_window(window_samples), m_rpm_cmd(k_nan), m_prev_counts(k_nan) {
  MCG_DEMAND(window_samples >= 1);
}

std::uint64_t StreamAssembler::lost_samples() const { return m_lost_blocks * MCG_STREAM_SAMPLES; }

void StreamAssembler::restart() { m_restarted = m_started; }

bool StreamAssembler::push(std::span<const std::uint8_t> payload, double arrival_gap_s) {
  if (payload.size() != MCG_STREAM_PAYLOAD) return false;
  const std::uint8_t seq = payload[0];
  std::int64_t step = 1;
  bool is_break = false;
  if (m_restarted) {
    // The sequence numbers may have restarted: only the wall-clock silence places the block.
    step = std::max<std::int64_t>(2, std::llround(std::clamp(arrival_gap_s, 0.0, 1e12) / k_block_s));
    is_break = true;
  } else if (m_started) {
    step = static_cast<std::uint8_t>(seq - m_last_seq);
    // Choose the unwrapped step nearest to what the silence since the last block suggests
    // (in closed form: a day's silence is no loop of 5000 turns).
    const double expected = std::min(arrival_gap_s, 1e12) / k_block_s;
    if (static_cast<double>(step) + 128.0 < expected) {
      step +=
          256 * static_cast<std::int64_t>(std::ceil((expected - 128.0 - static_cast<double>(step)) / 256.0));
    }
    if (step == 0) step = 256;
    is_break = step - 1 > k_max_filled_blocks;
  }
  m_restarted = false;
  if (m_started) m_block_index += step;
  m_rows.clear();
  if (step > 1) {
    // Lost blocks: a row per lost sample (one for a break), and nothing measured carries across.
    const std::int64_t first = (m_block_index - step + 1) * MCG_STREAM_SAMPLES;
    const std::int64_t end = is_break ? first + 1 : m_block_index * MCG_STREAM_SAMPLES;
    for (std::int64_t n = first; n < end; ++n) {
      m_rows.push_back({static_cast<double>(n) * k_sample_s, k_nan, k_nan, k_nan, k_nan, k_nan, k_nan});
    }
    m_lost_blocks += static_cast<std::uint64_t>(step - 1);
    if (is_break) ++m_breaks;
    m_window_counts.clear();
    m_prev_counts = k_nan;
    m_rpm_cmd = k_nan;
  }
  m_started = true;
  m_last_seq = seq;
  ++m_blocks;

  std::array<StreamSample, MCG_STREAM_SAMPLES> samples{};
  std::size_t first_cmd = MCG_STREAM_SAMPLES;
  std::size_t last_cmd = MCG_STREAM_SAMPLES;
  for (std::size_t k = 0; k < MCG_STREAM_SAMPLES; ++k) {
    samples[k] = decode_stream_sample(
        payload.subspan(MCG_STREAM_HEADER + k * MCG_STREAM_SAMPLE_BYTES).first<MCG_STREAM_SAMPLE_BYTES>());
    if (samples[k].rpm_cmd_written) {
      if (first_cmd == MCG_STREAM_SAMPLES) first_cmd = k;
      last_cmd = k;
    }
  }
  const double rpm_cmd_end = get_i16(payload, 1);
  if (first_cmd == MCG_STREAM_SAMPLES) m_rpm_cmd = rpm_cmd_end;  // unchanged all through the block

  const double rpm_per_pulse = 60.0 / (MCG_COUNTS_PER_REV * k_sample_s * m_window);
  for (std::size_t k = 0; k < MCG_STREAM_SAMPLES; ++k) {
    const StreamSample& s = samples[k];
    m_window_counts.push_back(m_prev_counts);
    while (m_window_counts.size() > static_cast<std::size_t>(m_window)) m_window_counts.pop_front();
    double rpm = k_nan;
    if (m_window_counts.size() == static_cast<std::size_t>(m_window)) {
      double sum = 0.0;
      for (const double c : m_window_counts) sum += c;
      rpm = sum * rpm_per_pulse;
    }
    double rpm_cmd = m_rpm_cmd;
    if (k >= last_cmd) {
      rpm_cmd = rpm_cmd_end;
    } else if (k >= first_cmd) {
      rpm_cmd = k_nan;  // changed twice within the block: the value in between is not reported
    }
    const std::int64_t n = m_block_index * MCG_STREAM_SAMPLES + static_cast<std::int64_t>(k);
    const double counts_row = m_prev_counts;
    m_rows.push_back({static_cast<double>(n) * k_sample_s, rpm, counts_row, s.duty_permille / static_cast<double>(MCG_DUTY_FULL),
                      rpm_cmd, s.clutch_engaged ? 2.0 : 1.0, s.load_closed ? 1.0 : 0.0});
    const bool saturated = std::abs(s.counts) >= MCG_STREAM_COUNTS_MAX;
    m_prev_counts = saturated ? k_nan : static_cast<double>(s.counts);
  }
  m_rpm_cmd = rpm_cmd_end;
  return true;
}

}  // namespace mcg::link
