// Excitation signals for identification: steps, staircases, chirps, multisines, PRBS, APRBS.
// Every generator returns the deviation x(t_k) from the bias on the grid t_k = k dt; the
// tool adds the bias and the held or scheduled clutch and r_load columns.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <random>
#include <span>
#include <string_view>
#include <vector>

namespace mcg::signal {

/// The most rows mcg-sweep writes for an excitation, or resamples a measured table to (a day
/// at 10 ms is 8.64e6 rows; the largest table takes about 160 MB while it is built). Options
/// whose product asks for more are refused, naming them, before anything is allocated.
inline constexpr std::size_t k_max_rows = 10'000'000;

/// The most terms (lines x samples of one period) a multisine computes: about 0.6 s of
/// one core.
inline constexpr double k_max_multisine_terms = 2e8;

/// One change of a piecewise-constant value: from `time_s` on, the value is `value`.
struct Change {
  double value;
  double time_s;
};

/// Parses "6@0.5,0@0.8" (value@time, times strictly increasing, both finite; r_load values
/// may be `inf`). Throws mcg::Error naming `option` and the offending item.
std::vector<Change> parse_schedule(std::string_view text, std::string_view option);

/// A schedule read at times that never decrease (the rows of a table): holds `initial` until its
/// first change. A change acts from the first time t_s with change.time_s <= t_s + 0.5 ns, so
/// that a change at 0.1 s lands on the sample that prints as 0.1.
class ScheduleCursor {
 public:
  ScheduleCursor(double initial, std::span<const Change> changes) : m_value(initial), m_changes(changes) {}
  /// The value at t_s (not before the previous call's t_s).
  double at(double t_s) {
    while (m_next < m_changes.size() && m_changes[m_next].time_s <= t_s + 5e-10)
      m_value = m_changes[m_next++].value;
    return m_value;
  }

 private:
  double m_value;
  std::span<const Change> m_changes;
  std::size_t m_next = 0;
};

/// Value at `t_s` of a schedule that holds `initial` until its first change (ScheduleCursor's rule).
double schedule_value(double initial, std::span<const Change> changes, double t_s);

/// Samples of dt_s in [0, duration): floor(duration_s / dt_s) (a duration within 1e-9 of a
/// whole number of steps counts as whole), nullopt when more than k_max_rows.
std::optional<std::size_t> grid_samples(double dt_s, double duration_s);

/// The sample grid t_k = k dt_s for k = 0 .. n-1, n = grid_samples() (at most k_max_rows:
/// the caller has checked, MCG_DEMAND). Rows cover [0, duration).
std::vector<double> time_grid(double dt_s, double duration_s);

/// Step sequence: 0 before `at_s`, `level` from `at_s`, then each further change of `then`
/// (whose times must come after `at_s`; throws otherwise).
std::vector<double> step_signal(std::span<const double> t_s, double level, double at_s,
                                std::span<const Change> then);

/// The 4N+1 levels of a slow staircase through zero in both directions, N = `steps`:
/// 0, A/N, ..., A, (N-1)A/N, ..., 0, ..., -A, ..., -A/N, 0 (A = `amp`).
std::vector<double> staircase_levels(double amp, int steps);

/// Staircase: level j of staircase_levels() held over [j hold_s, (j+1) hold_s); the last
/// level holds to the end.
std::vector<double> staircase_signal(std::span<const double> t_s, double amp, int steps, double hold_s);

enum class ChirpSpacing { linear, log };

/// Swept sine x(t) = A sin(phi(t)) over [0, T] from f0 to f1 (Hz):
///   linear: phi = 2 pi (f0 t + (f1 - f0) t^2 / (2 T)),   f(t) = f0 + (f1 - f0) t / T
///   log:    phi = 2 pi f0 T (k^(t/T) - 1) / ln k, k = f1/f0,   f(t) = f0 k^(t/T)
std::vector<double> chirp_signal(std::span<const double> t_s, double amp, double f0_hz, double f1_hz,
                                 double duration_s, ChirpSpacing spacing);

/// Harmonic numbers h (line frequency h / period_s) for `lines` lines spread between f0 and
/// f1 Hz, linearly or logarithmically, each rounded to the nearest harmonic and made
/// distinct by moving up. Throws when f0 < 1/period or the band holds fewer harmonics.
std::vector<int> multisine_harmonics(double f0_hz, double f1_hz, int lines, double period_s,
                                     ChirpSpacing spacing);

/// Schroeder's phases for K equal-amplitude lines: phi_k = -pi k (k - 1) / K, k = 1..K.
/// They keep the crest factor of a flat multisine near 1.7 instead of sqrt(2K).
std::vector<double> schroeder_phases(std::size_t count);

/// Multisine periodic in `period_samples` samples of dt:
///   x_k = s sum_j cos(2 pi h_j k / period_samples + phi_j),
/// with s chosen so that max |x| over one period equals `amp` (the peak the user asked for).
std::vector<double> multisine_signal(std::size_t samples, double amp, std::size_t period_samples,
                                     std::span<const int> harmonics, std::span<const double> phases_rad);

/// max |x| / rms(x); 0 for an all-zero or empty signal.
double crest_factor(std::span<const double> x);

/// Orders of maximal-length sequences offered (shift register length n, period 2^n - 1).
inline constexpr int k_prbs_min_order = 2;
inline constexpr int k_prbs_max_order = 24;

/// Fibonacci linear-feedback shift register with the maximal-length taps of order n.
class Lfsr {
 public:
  /// `state` must be nonzero in the low n bits (MCG_DEMAND).
  Lfsr(int order, std::uint32_t state);
  /// The next output bit (0 or 1).
  int next();
  std::uint32_t state() const { return m_state; }

 private:
  int m_order;
  std::uint32_t m_mask;
  std::uint32_t m_state;
};

/// A nonzero initial register state drawn from `rng`.
std::uint32_t prbs_initial_state(int order, std::mt19937_64& rng);

/// PRBS: +amp for bit 1, -amp for bit 0, one bit every `clock_samples` samples.
std::vector<double> prbs_signal(std::size_t samples, double amp, int order, std::size_t clock_samples,
                                std::uint32_t state);

/// Amplitude-modulated PRBS: the PRBS's runs of equal bits (its switching instants) kept,
/// each run given a level drawn uniformly from [-amp, amp] by `rng`.
std::vector<double> aprbs_signal(std::size_t samples, double amp, int order, std::size_t clock_samples,
                                 std::uint32_t state, std::mt19937_64& rng);

}  // namespace mcg::signal
