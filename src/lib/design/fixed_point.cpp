// Quantisation of a designed controller into the board's registers.
#include "design/fixed_point.hpp"

#include "common/error.hpp"
#include "config/ini.hpp"
#include "mcg_protocol.h"  // MCG_COUNTS_PER_REV, MCG_DUTY_FULL, MCG_COEF_FRAC_BITS_MAX, MCG_TICK_US

#include <cmath>
#include <cstddef>

namespace mcg::design {

namespace {

constexpr double k_coef_max = 32767.0;   ///< int16 register
constexpr double k_e_max_q8 = 8191.0;    ///< |e| bound in Q8 pulses per tick (-8191 <= e <= r <= 6291)
constexpr double k_acc_limit = 2147483647.0;

}  // namespace

double DesignUnits::factor() const {
  // The same expression as mcg-serial's (src/lib/link/controller_ini.cpp), so both round alike.
  return input_scale * (60000.0 / MCG_COUNTS_PER_REV) * (MCG_DUTY_FULL / duty_full_scale);
}

std::optional<BoardFixedPoint> board_fixed_point(const std::vector<double>& b, const std::vector<double>& a,
                                                 const DesignUnits& units) {
  if (std::fabs(units.dt_s - MCG_TICK_US * 1e-6) > 1e-12) return std::nullopt;
  if (a.empty() || a[0] == 0.0 || b.empty()) return std::nullopt;
  const bool incremental = a.size() == 2 && a[1] == -a[0];
  if (!(a.size() == 1 || incremental)) return std::nullopt;
  if ((!incremental && b.size() != 1) || (incremental && b.size() < 2) || b.size() > 3) return std::nullopt;

  BoardFixedPoint q;
  q.mode = !incremental ? "p" : b.size() == 3 ? "pid" : "pi";
  q.factor = units.factor();
  const double scale = q.factor / a[0];
  std::vector<double> g;
  double largest = 0.0;
  std::size_t k_largest = 0;
  for (std::size_t k = 0; k < b.size(); ++k) {
    g.push_back(b[k] * scale);
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
    q.regs.push_back(static_cast<std::int32_t>(v));
    sum += std::fabs(v);
    q.b.push_back(std::ldexp(v, -f) / q.factor);
  }
  if (incremental && q.regs.size() == 2) q.regs.push_back(0);
  q.a = incremental ? std::vector<double>{1.0, -1.0} : std::vector<double>{1.0};
  q.acc_max = MCG_DUTY_FULL * std::ldexp(1.0, f + 8) + k_e_max_q8 * sum;
  if (q.acc_max > k_acc_limit) {
    fail("fixed point: the accumulator can reach {} > 2^31 - 1 at coef_frac = {}", config::format_number(q.acc_max), f);
  }
  return q;
}

}  // namespace mcg::design
