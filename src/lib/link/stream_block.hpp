// Stream blocks (MCG_MSG_STREAM) to rows of samples: sequence unwrapping, gaps, the rpm window.
#pragma once

#include <cstdint>
#include <deque>
#include <span>
#include <vector>

namespace mcg::link {

/// One 2 ms sample of the stream, in the data contract's units.
struct StreamRow {
  double t_s;       ///< end of the sample's 2 ms, s since the end of the first sample
  double rpm;       ///< pulses over the trailing window / 2048 / window * 60; NaN until the window
                    ///< is filled with received, unsaturated samples
  double counts;    ///< pulses during the 2 ms (255 = saturated)
  double duty;      ///< -1..1, the last block-end report; NaN before the first
  double rpm_cmd;   ///< rpm, likewise
};

/// Turns stream blocks into rows. Each block carries a sequence number (mod 256), 16 samples
/// of 2 ms and the duty and rpm_cmd at its last sample. A block whose sequence number skips
/// k numbers follows k lost blocks (16 k lost samples); t keeps counting through the gap so
/// the time axis stays true. The wrap is resolved with the arrival time: a gap of g seconds
/// since the previous block means about g / 0.032 blocks, so 8 s without data does not read
/// as a small gap.
class StreamAssembler {
 public:
  /// `window_samples`: the rpm estimator's window in 2 ms samples (>= 1).
  explicit StreamAssembler(int window_samples);

  /// Adds one block's payload that arrived `arrival_gap_s` after the previous one. Returns
  /// false for a malformed payload (ignored). Afterwards rows() holds its 16 rows.
  bool push(std::span<const std::uint8_t> payload, double arrival_gap_s);
  const std::vector<StreamRow>& rows() const { return m_rows; }
  std::uint64_t lost_samples() const { return m_lost_blocks * 16u; }
  std::uint64_t blocks() const { return m_blocks; }

 private:
  int m_window;
  bool m_started = false;
  std::uint8_t m_last_seq = 0;
  std::int64_t m_block_index = 0;    ///< unwrapped index of the last block
  std::uint64_t m_lost_blocks = 0;
  std::uint64_t m_blocks = 0;
  double m_duty = 0.0;
  double m_rpm_cmd = 0.0;
  bool m_have_report = false;
  std::deque<int> m_window_counts;   ///< the last samples; -1 marks a lost or saturated one
  std::vector<StreamRow> m_rows;
};

}  // namespace mcg::link
