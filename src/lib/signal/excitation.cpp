// Excitation generators: piecewise-constant schedules, sweeps, multisines, shift registers.
#include "signal/excitation.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <string>

#include "common/checked.hpp"
#include "common/demand.hpp"
#include "common/error.hpp"
#include "common/text.hpp"
#include "common/units.hpp"

namespace mcg::signal {

namespace {

bool parse_double(std::string_view text, double& value) {
  text = trim(text);
  if (text.empty()) return false;
  if (text.front() == '+') text.remove_prefix(1);
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size();
}

// Tap positions (polynomial exponents) of maximal-length Fibonacci registers, order 2..24.
// From the standard tables (e.g. Xilinx XAPP052); the unit tests check every order's period.
constexpr std::array<std::array<int, 4>, 25> k_taps = {{
    {0, 0, 0, 0},     {0, 0, 0, 0},      {2, 1, 0, 0},      {3, 2, 0, 0},     {4, 3, 0, 0},
    {5, 3, 0, 0},     {6, 5, 0, 0},      {7, 6, 0, 0},      {8, 6, 5, 4},     {9, 5, 0, 0},
    {10, 7, 0, 0},    {11, 9, 0, 0},     {12, 11, 10, 4},   {13, 12, 11, 8},  {14, 13, 12, 2},
    {15, 14, 0, 0},   {16, 15, 13, 4},   {17, 14, 0, 0},    {18, 11, 0, 0},   {19, 18, 17, 14},
    {20, 17, 0, 0},   {21, 19, 0, 0},    {22, 21, 0, 0},    {23, 18, 0, 0},   {24, 23, 22, 17},
}};

}  // namespace

std::vector<Change> parse_schedule(std::string_view text, std::string_view option) {
  std::vector<Change> changes;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t comma = text.find(',', start);
    if (comma == std::string_view::npos) comma = text.size();
    const std::string_view item = trim(text.substr(start, comma - start));
    const std::size_t at = item.find('@');
    if (item.empty()) fail("{}: empty item in {} (expected value@time, e.g. 6@0.5)", option, quote(text));
    if (at == std::string_view::npos) fail("{}: {} is not value@time (e.g. 6@0.5)", option, quote(item));
    Change change{};
    if (!parse_double(item.substr(0, at), change.value) || std::isnan(change.value)) {
      fail("{}: invalid value {} in {}", option, quote(trim(item.substr(0, at))), quote(item));
    }
    if (!parse_double(item.substr(at + 1), change.time_s) || !std::isfinite(change.time_s)) {
      fail("{}: invalid time {} in {}", option, quote(trim(item.substr(at + 1))), quote(item));
    }
    if (change.time_s < 0) fail("{}: negative time in {}", option, quote(item));
    if (!changes.empty() && change.time_s <= changes.back().time_s) {
      fail("{}: times must increase ({} after {}@{})", option, quote(item), changes.back().value,
           changes.back().time_s);
    }
    changes.push_back(change);
    start = comma + 1;
  }
  return changes;
}

double schedule_value(double initial, std::span<const Change> changes, double t_s) {
  return ScheduleCursor(initial, changes).at(t_s);
}

std::optional<std::size_t> grid_samples(double dt_s, double duration_s) {
  MCG_DEMAND(dt_s > 0 && duration_s > 0);
  return to_integer(std::floor(duration_s / dt_s + 1e-9), std::size_t{0}, k_max_rows);
}

std::vector<double> time_grid(double dt_s, double duration_s) {
  const std::optional<std::size_t> n = grid_samples(dt_s, duration_s);
  MCG_DEMAND(n.has_value());
  std::vector<double> t(*n);
  for (std::size_t k = 0; k < *n; ++k) t[k] = static_cast<double>(k) * dt_s;
  return t;
}

std::vector<double> step_signal(std::span<const double> t_s, double level, double at_s,
                                std::span<const Change> then) {
  if (!then.empty() && then.front().time_s <= at_s) {
    fail("--then: {}@{} does not come after --at {}", then.front().value, then.front().time_s, at_s);
  }
  std::vector<Change> changes{{level, at_s}};
  changes.insert(changes.end(), then.begin(), then.end());
  std::vector<double> x(t_s.size());
  ScheduleCursor value(0.0, changes);
  for (std::size_t k = 0; k < t_s.size(); ++k) x[k] = value.at(t_s[k]);
  return x;
}

std::vector<double> staircase_levels(double amp, int steps) {
  MCG_DEMAND(steps >= 1);
  const double n = static_cast<double>(steps);
  std::vector<double> levels;
  levels.reserve(static_cast<std::size_t>(4 * steps + 1));
  for (int j = 0; j <= steps; ++j) levels.push_back(amp * j / n);
  for (int j = steps - 1; j >= -steps; --j) levels.push_back(amp * j / n);
  for (int j = -steps + 1; j <= 0; ++j) levels.push_back(amp * j / n);
  return levels;
}

std::vector<double> staircase_signal(std::span<const double> t_s, double amp, int steps, double hold_s) {
  MCG_DEMAND(hold_s > 0);
  const std::vector<double> levels = staircase_levels(amp, steps);
  std::vector<double> x(t_s.size());
  for (std::size_t k = 0; k < t_s.size(); ++k) {
    const auto index =
        clamp_to_integer(std::floor(t_s[k] / hold_s + 1e-9), std::size_t{0}, levels.size() - 1);
    x[k] = levels[index];
  }
  return x;
}

std::vector<double> chirp_signal(std::span<const double> t_s, double amp, double f0_hz, double f1_hz,
                                 double duration_s, ChirpSpacing spacing) {
  MCG_DEMAND(f0_hz > 0 && f1_hz > 0 && duration_s > 0);
  std::vector<double> x(t_s.size());
  const double k = f1_hz / f0_hz;
  const bool linear = spacing == ChirpSpacing::linear || std::abs(k - 1.0) < 1e-12;
  for (std::size_t i = 0; i < t_s.size(); ++i) {
    const double t = t_s[i];
    const double phase =
        linear ? 2.0 * k_pi * (f0_hz * t + (f1_hz - f0_hz) * t * t / (2.0 * duration_s))
               : 2.0 * k_pi * f0_hz * duration_s * std::expm1(std::log(k) * t / duration_s) / std::log(k);
    x[i] = amp * std::sin(phase);
  }
  return x;
}

std::vector<int> multisine_harmonics(double f0_hz, double f1_hz, int lines, double period_s,
                                     ChirpSpacing spacing) {
  MCG_DEMAND(lines >= 1 && period_s > 0 && f1_hz >= f0_hz);
  const double h0 = f0_hz * period_s;
  const double h1 = f1_hz * period_s;
  if (h0 < 1.0 - 1e-9) {
    fail("--f0 {} Hz is below the base frequency 1/period = {} Hz", f0_hz, 1.0 / period_s);
  }
  // Harmonics are ints: a band beyond them is refused (the caller bounds the period's samples).
  const std::optional<int> lowest_h = to_integer(std::round(h0), 1, std::numeric_limits<int>::max());
  const std::optional<int> highest_h = to_integer(std::floor(h1 + 1e-9), 1, std::numeric_limits<int>::max());
  if (!lowest_h || !highest_h) {
    fail("--f0 {} Hz, --f1 {} Hz: more harmonics of 1/period = {} Hz than a multisine numbers", f0_hz, f1_hz,
         1.0 / period_s);
  }
  const int lowest = *lowest_h;
  const int highest = *highest_h;
  if (highest - lowest + 1 < lines) {
    fail("--lines {}: the band {}..{} Hz holds only {} harmonics of 1/period = {} Hz", lines, f0_hz, f1_hz,
         std::max(0, highest - lowest + 1), 1.0 / period_s);
  }
  std::vector<int> h;
  for (int j = 0; j < lines; ++j) {
    const double u = lines == 1 ? 0.0 : static_cast<double>(j) / (lines - 1);
    const double target = spacing == ChirpSpacing::log ? h0 * std::pow(h1 / h0, u) : h0 + (h1 - h0) * u;
    int harmonic = clamp_to_integer(std::round(target), lowest, highest);
    if (!h.empty() && harmonic <= h.back()) harmonic = h.back() + 1;
    h.push_back(harmonic);
  }
  // Moving up may have pushed the top lines past f1: pull them back down, keeping them distinct.
  for (std::size_t j = h.size(); j-- > 0;) {
    const int cap = highest - static_cast<int>(h.size() - 1 - j);
    if (h[j] > cap) h[j] = cap;
  }
  return h;
}

std::vector<double> schroeder_phases(std::size_t count) {
  std::vector<double> phi(count);
  const double k_count = static_cast<double>(count);
  for (std::size_t j = 0; j < count; ++j) {
    const double k = static_cast<double>(j + 1);
    phi[j] = std::remainder(-k_pi * k * (k - 1.0) / k_count, 2.0 * k_pi);
  }
  return phi;
}

/// Samples between exact values of a multisine line's rotation (its error grows by an ulp a step).
constexpr std::size_t k_multisine_exact = 64;

std::vector<double> multisine_signal(std::size_t samples, double amp, std::size_t period_samples,
                                     std::span<const int> harmonics, std::span<const double> phases_rad) {
  MCG_DEMAND(harmonics.size() == phases_rad.size() && period_samples > 0);
  const double np = static_cast<double>(period_samples);
  std::vector<double> period(period_samples, 0.0);
  for (std::size_t j = 0; j < harmonics.size(); ++j) {
    MCG_DEMAND(harmonics[j] > 0);
    const std::size_t h = static_cast<std::size_t>(harmonics[j]) % period_samples;
    // e^(i(2π h k / N + φ)) by rotating with e^(i 2π h / N), a few ulps a step, taken afresh
    // every k_multisine_exact samples from h k modulo N (kept by adding h, small and exact): a
    // cosine per term cost 13 ns, the rotation 1.5.
    const double step = 2.0 * k_pi * static_cast<double>(h) / np;
    const double wc = std::cos(step);
    const double ws = std::sin(step);
    double re = 0.0;
    double im = 0.0;
    std::size_t hk = 0;
    for (std::size_t k = 0; k < period_samples; ++k) {
      if (k % k_multisine_exact == 0) {
        const double angle = 2.0 * k_pi * static_cast<double>(hk) / np + phases_rad[j];
        re = std::cos(angle);
        im = std::sin(angle);
      }
      period[k] += re;
      const double next_re = re * wc - im * ws;
      im = re * ws + im * wc;
      re = next_re;
      hk += h;
      if (hk >= period_samples) hk -= period_samples;
    }
  }
  double peak = 0.0;
  for (double v : period) peak = std::max(peak, std::abs(v));
  const double scale = peak > 0 ? amp / peak : 0.0;
  std::vector<double> x(samples);
  for (std::size_t k = 0; k < samples; ++k) x[k] = scale * period[k % period_samples];
  return x;
}

double crest_factor(std::span<const double> x) {
  double peak = 0.0;
  double sum_sq = 0.0;
  for (double v : x) {
    peak = std::max(peak, std::abs(v));
    sum_sq += v * v;
  }
  if (x.empty() || sum_sq == 0.0) return 0.0;
  return peak / std::sqrt(sum_sq / static_cast<double>(x.size()));
}

Lfsr::Lfsr(int order, std::uint32_t state)
    : m_order(order), m_mask(static_cast<std::uint32_t>((std::uint64_t{1} << order) - 1)), m_state(state) {
  MCG_DEMAND(order >= k_prbs_min_order && order <= k_prbs_max_order);
  m_state &= m_mask;
  MCG_DEMAND(m_state != 0);
}

int Lfsr::next() {
  const auto& taps = k_taps[static_cast<std::size_t>(m_order)];
  std::uint32_t bit = 0;
  for (int tap : taps) {
    if (tap > 0) bit ^= m_state >> (m_order - tap);
  }
  bit &= 1U;
  const auto out = static_cast<int>(m_state & 1U);
  m_state = (m_state >> 1) | (bit << (m_order - 1));
  return out;
}

std::uint32_t prbs_initial_state(int order, std::mt19937_64& rng) {
  const auto max_state = static_cast<std::uint32_t>((std::uint64_t{1} << order) - 1);
  std::uniform_int_distribution<std::uint32_t> pick(1, max_state);
  return pick(rng);
}

std::vector<double> prbs_signal(std::size_t samples, double amp, int order, std::size_t clock_samples,
                                std::uint32_t state) {
  MCG_DEMAND(clock_samples >= 1);
  Lfsr lfsr(order, state);
  std::vector<double> x(samples);
  double value = 0.0;
  for (std::size_t k = 0; k < samples; ++k) {
    if (k % clock_samples == 0) value = lfsr.next() != 0 ? amp : -amp;
    x[k] = value;
  }
  return x;
}

std::vector<double> aprbs_signal(std::size_t samples, double amp, int order, std::size_t clock_samples,
                                 std::uint32_t state, std::mt19937_64& rng) {
  MCG_DEMAND(clock_samples >= 1);
  Lfsr lfsr(order, state);
  std::uniform_real_distribution<double> level(-amp, amp);
  std::vector<double> x(samples);
  int bit = -1;
  double value = 0.0;
  for (std::size_t k = 0; k < samples; ++k) {
    if (k % clock_samples == 0) {
      const int next = lfsr.next();
      if (next != bit) value = level(rng);
      bit = next;
    }
    x[k] = value;
  }
  return x;
}

}  // namespace mcg::signal
