// Stream blocks (MCG_MSG_STREAM, protocol 2) to rows of samples: sequence unwrapping, gaps, the rpm window.
#pragma once

#include <cstdint>
#include <deque>
#include <span>
#include <vector>

namespace mcg::link {

/// One row of the stream in the data contract's convention (mcg-csv(5)): duty, clutch, load and
/// rpm_cmd act over [t, t + P); counts and rpm are measured up to t (P = MCG_STREAM_PERIOD_MS).
struct StreamRow {
  double t_s;       ///< n P, s, n counted from the first sample of the first block received
  double rpm;       ///< signed pulses over (t - W, t] / 2048 / W * 60; NaN until the window holds
                    ///< W received, unsaturated samples (W = the estimator window)
  double counts;    ///< signed pulses over (t - P, t]; NaN when not received
  double duty;      ///< -1..1, mean PWM duty over [t, t + P)
  double rpm_cmd;   ///< rpm in force over [t, t + P); NaN where a block changed it twice
  double clutch;    ///< mcg-csv clutch state: 1 attached and disengaged, 2 engaged
  double load;      ///< 1 the load relay closed, 0 open
};

/// Turns stream blocks into rows. Each block carries a sequence number (mod 256) and 16
/// samples of 4 ms. A block whose sequence number skips k numbers follows k lost blocks (16 k
/// lost samples): rows() then starts with a row per lost sample, t filled in and every other
/// field NaN, so the time axis stays true and a tool driven by the capture stops at the gap. The wrap is
/// resolved with the arrival time: a gap of g seconds since the previous block means about
/// g / 0.064 blocks, so 20 s without data does not read as a small gap.
///
/// A gap longer than k_max_filled_blocks (the sequence number's range, about 16 s: a laptop
/// suspended, a port that came back) is a break instead: one row, t of the first missing
/// sample and every other field NaN, then the block at its own t. The work and memory of a
/// push stay bounded whatever the silence.
class StreamAssembler {
 public:
  /// `window_samples`: the rpm estimator's window in samples (>= 1).
  explicit StreamAssembler(int window_samples);

  /// Adds one block's payload that arrived `arrival_gap_s` after the previous one. Returns
  /// false for a malformed payload (ignored). Afterwards rows() holds its 16 rows.
  bool push(std::span<const std::uint8_t> payload, double arrival_gap_s);
  const std::vector<StreamRow>& rows() const { return m_rows; }
  std::uint64_t lost_samples() const;
  std::uint64_t blocks() const { return m_blocks; }
  /// Breaks (gaps longer than k_max_filled_blocks, and restarts) so far.
  std::uint64_t breaks() const { return m_breaks; }
  /// The line was lost and came back (the board may have restarted its sequence numbers):
  /// the next block follows a break, placed by its arrival gap alone.
  void restart();

  /// Longest gap, in blocks, filled with a row per lost sample.
  static constexpr std::int64_t k_max_filled_blocks = 256;

 private:
  int m_window;
  bool m_started = false;
  std::uint8_t m_last_seq = 0;
  std::int64_t m_block_index = 0;    ///< unwrapped index of the last block
  std::uint64_t m_lost_blocks = 0;
  std::uint64_t m_blocks = 0;
  std::uint64_t m_breaks = 0;
  bool m_restarted = false;          ///< the next push follows a restart
  double m_rpm_cmd;                  ///< in force at the end of the last block (NaN: unknown)
  double m_prev_counts;              ///< counts of the last sample, for the next row (NaN: none)
  std::deque<double> m_window_counts;   ///< the last samples; NaN marks a lost or saturated one
  std::vector<StreamRow> m_rows;
};

/// The fields of one 3-byte stream sample (mcg_protocol.h, "Stream blocks").
struct StreamSample {
  int duty_permille;   ///< -1024..1023
  int counts;          ///< -512..511
  bool clutch_engaged;
  bool load_closed;
  bool rpm_cmd_written;
};
StreamSample decode_stream_sample(std::span<const std::uint8_t, 3> bytes);

}  // namespace mcg::link
