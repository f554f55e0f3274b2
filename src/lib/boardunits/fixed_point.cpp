// Quantisation of a designed controller into the board's registers.
#include "boardunits/fixed_point.hpp"

#include <cmath>
#include <cstddef>

#include "common/checked.hpp"
#include "common/demand.hpp"
#include "common/error.hpp"
#include "config/ini.hpp"
#include "mcg_protocol.h"  // MCG_COEF_FRAC_BITS_MAX, MCG_ERR_LIMIT, MCG_ERR_FRAC_BITS, MCG_MODE_*, MCG_REG_*

namespace mcg::boardunits {

namespace {

constexpr double k_coef_max = 32767.0;   ///< int16 register
constexpr double k_e_max_q8 = MCG_ERR_LIMIT;    ///< |e| bound in Q8 pulses per tick (-8191 <= e <= r <= 6291)
constexpr double k_acc_limit = 2147483647.0;

static_assert(k_board_modes[MCG_MODE_OPEN] == "open" && k_board_modes[MCG_MODE_P] == "p" &&
              k_board_modes[MCG_MODE_PI] == "pi" && k_board_modes[MCG_MODE_PID] == "pid");

}  // namespace

std::optional<std::int16_t> board_mode(std::string_view name) {
  for (std::size_t k = 0; k < k_board_modes.size(); ++k) {
    if (k_board_modes[k] == name) return static_cast<std::int16_t>(k);
  }
  return std::nullopt;
}

std::vector<BoardRegisterValue> board_registers(const BoardFixedPoint& q) {
  const std::optional<std::int16_t> mode = board_mode(q.mode);
  MCG_DEMAND(mode && *mode != MCG_MODE_OPEN);
  const bool p = *mode == MCG_MODE_P;
  MCG_DEMAND(q.regs.size() == (p ? 1u : 3u));
  // A set of registers read back (no design behind it) wants what it holds.
  const auto wanted = [&](std::size_t k) {
    return k < q.wanted.size() ? q.wanted[k] : std::ldexp(static_cast<double>(q.regs[k]), -q.coef_frac);
  };
  std::vector<BoardRegisterValue> out{
      {MCG_REG_COEF_FRAC, static_cast<std::int16_t>(q.coef_frac), static_cast<double>(q.coef_frac)}};
  static constexpr std::uint8_t k_gains[] = {MCG_REG_B0, MCG_REG_B1, MCG_REG_B2};
  for (std::size_t k = 0; k < q.regs.size(); ++k) {
    out.push_back(
        {p ? std::uint8_t{MCG_REG_KP} : k_gains[k], static_cast<std::int16_t>(q.regs[k]), wanted(k)});
  }
  out.push_back({MCG_REG_MODE, *mode, static_cast<double>(*mode)});
  return out;
}

double ControllerUnits::factor() const {
  return input_scale * (k_ms_per_min / k_board_counts_per_rev) * (k_board_duty_full / duty_full_scale);
}

std::optional<BoardFixedPoint> board_fixed_point(const std::vector<double>& b, const std::vector<double>& a,
                                                 const ControllerUnits& units) {
  if (std::fabs(units.dt_s - k_tick_s) > 1e-12) return std::nullopt;
  if (a.empty() || a[0] == 0.0 || b.empty()) return std::nullopt;
  const bool incremental = a.size() == 2 && a[1] == -a[0];
  if (!(a.size() == 1 || incremental)) return std::nullopt;
  if ((!incremental && b.size() != 1) || (incremental && b.size() < 2) || b.size() > 3) return std::nullopt;

  BoardFixedPoint q;
  q.mode = k_board_modes[!incremental ? MCG_MODE_P : b.size() == 3 ? MCG_MODE_PID : MCG_MODE_PI];
  q.factor = units.factor();
  const double scale = q.factor / a[0];
  std::vector<double> g;
  double largest = 0.0;
  std::size_t k_largest = 0;
  for (std::size_t k = 0; k < b.size(); ++k) {
    g.push_back(b[k] * scale);
    if (std::isnan(g[k])) {
      fail("fixed point: b{} = {} is {} on the board (b{} x {} / a0)", k, config::format_number(b[k]),
           config::format_number(g[k]), k, config::format_number(q.factor));
    }
    if (std::fabs(g[k]) > largest) k_largest = k;
    largest = std::fmax(largest, std::fabs(g[k]));
  }
  int f = static_cast<int>(MCG_COEF_FRAC_BITS_MAX);
  while (f >= 0 && std::round(std::ldexp(largest, f)) > k_coef_max) --f;
  if (f < 0) {
    fail("fixed point: b{} = {} is {} /1000 duty per pulse/ms on the board, beyond its 16 bits even at coef_frac = 0",
         k_largest, config::format_number(b[k_largest]), config::format_number(g[k_largest]));
  }
  q.coef_frac = f;
  double sum = 0.0;
  for (std::size_t k = 0; k < g.size(); ++k) {
    const double v = std::round(std::ldexp(g[k], f));
    if (v == 0.0 && g[k] != 0.0) {
      fail("fixed point: b{} = {} rounds to 0 in the board's Q{}.{} (the controller would change structure)", k,
           config::format_number(b[k]), 15 - f, f);
    }
    const std::optional<std::int32_t> reg = to_integer(v, std::int32_t{-32768}, std::int32_t{32767});
    MCG_DEMAND(reg.has_value());  // coef_frac was chosen so that the largest fits
    q.regs.push_back(*reg);
    q.wanted.push_back(g[k]);
    sum += std::fabs(v);
    q.b.push_back(std::ldexp(v, -f) / q.factor);
  }
  if (incremental && q.regs.size() == 2) {
    q.regs.push_back(0);
    q.wanted.push_back(0.0);
  }
  q.a = incremental ? std::vector<double>{1.0, -1.0} : std::vector<double>{1.0};
  q.acc_max = k_board_duty_full * std::ldexp(1.0, f + static_cast<int>(MCG_ERR_FRAC_BITS)) + k_e_max_q8 * sum;
  if (q.acc_max > k_acc_limit) {
    fail("fixed point: the accumulator can reach {} > 2^31 - 1 at coef_frac = {}", config::format_number(q.acc_max), f);
  }
  return q;
}

}  // namespace mcg::boardunits
