// Stream block assembly.
#include "link/stream_block.hpp"

#include <cassert>
#include <algorithm>
#include <cmath>
#include <limits>

#include "link/frame.hpp"  // get_i16
#include "mcg_protocol.h"  // MCG_STREAM_*

namespace mcg::link {

namespace {

constexpr double k_sample_s = MCG_STREAM_PERIOD_MS * 1e-3;
constexpr double k_block_s = k_sample_s * MCG_STREAM_SAMPLES;
constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

}  // namespace

StreamAssembler::StreamAssembler(int window_samples) : m_window(window_samples) { assert(window_samples >= 1); }

bool StreamAssembler::push(std::span<const std::uint8_t> payload, double arrival_gap_s) {
  if (payload.size() != MCG_STREAM_HEADER + MCG_STREAM_SAMPLES) return false;
  const std::uint8_t seq = payload[0];
  std::int64_t step = 1;
  if (m_started) {
    step = static_cast<std::uint8_t>(seq - m_last_seq);
    // Choose the unwrapped step nearest to what the silence since the last block suggests.
    const double expected = arrival_gap_s / k_block_s;
    while (static_cast<double>(step) + 128.0 < expected) step += 256;
    if (step == 0) step = 256;
    m_lost_blocks += static_cast<std::uint64_t>(step - 1);
    const std::int64_t gap = std::min<std::int64_t>((step - 1) * MCG_STREAM_SAMPLES, m_window);
    for (std::int64_t k = 0; k < gap; ++k) m_window_counts.push_back(-1);
    m_block_index += step;
  }
  m_started = true;
  m_last_seq = seq;
  ++m_blocks;

  m_rows.clear();
  const double duty = get_i16(payload, 1) / static_cast<double>(MCG_DUTY_FULL);
  const double rpm_cmd = get_i16(payload, 3);
  const double rpm_per_pulse = 60.0 / (MCG_COUNTS_PER_REV * k_sample_s * m_window);
  for (std::size_t k = 0; k < MCG_STREAM_SAMPLES; ++k) {
    const int counts = payload[MCG_STREAM_HEADER + k];
    m_window_counts.push_back(counts == 255 ? -1 : counts);
    while (m_window_counts.size() > static_cast<std::size_t>(m_window)) m_window_counts.pop_front();
    double rpm = k_nan;
    if (m_window_counts.size() == static_cast<std::size_t>(m_window)) {
      int sum = 0;
      for (const int c : m_window_counts) sum = c < 0 || sum < 0 ? -1 : sum + c;
      if (sum >= 0) rpm = sum * rpm_per_pulse;
    }
    const bool last = k + 1 == MCG_STREAM_SAMPLES;
    if (last) {
      m_duty = duty;
      m_rpm_cmd = rpm_cmd;
      m_have_report = true;
    }
    const std::int64_t n = m_block_index * MCG_STREAM_SAMPLES + static_cast<std::int64_t>(k);
    m_rows.push_back({static_cast<double>(n) * k_sample_s, rpm, static_cast<double>(counts),
                      m_have_report ? m_duty : k_nan, m_have_report ? m_rpm_cmd : k_nan});
  }
  return true;
}

}  // namespace mcg::link
