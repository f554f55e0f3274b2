// Residual analysis for the gap diagnosis (see diag_residual.hpp for the definitions).
#include "fit/diag_residual.hpp"

#include <fmt/format.h>
#include <unsupported/Eigen/FFT>

#include <algorithm>
#include "common/demand.hpp"
#include <cmath>
#include <complex>
#include <limits>

namespace mcg::fit {

namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

bool relay_closed(double r_load_ohm) { return std::isfinite(r_load_ohm); }

/// Accumulates squared residuals of one regime.
struct Accumulator {
  double sum_sq = 0.0;
  std::size_t count = 0;
  void add(double r) {
    sum_sq += r * r;
    ++count;
  }
};

RegimeStat make_stat(std::string group, std::string regime, const Accumulator& acc, double total_sq) {
  RegimeStat s;
  s.group = std::move(group);
  s.regime = std::move(regime);
  s.samples = acc.count;
  s.rms = acc.count > 0 ? std::sqrt(acc.sum_sq / static_cast<double>(acc.count)) : k_nan;
  s.share = total_sq > 0.0 ? acc.sum_sq / total_sq : 0.0;
  return s;
}

/// RMS of the second difference over the rows where `use(n)` holds, divided by sqrt(6).
template <typename Use>
double second_difference_noise(std::span<const double> y, Use use) {
  double sum_sq = 0.0;
  std::size_t count = 0;
  for (std::size_t n = 1; n + 1 < y.size(); ++n) {
    if (!use(n - 1) || !use(n) || !use(n + 1)) continue;
    const double d = y[n + 1] - 2.0 * y[n] + y[n - 1];
    if (!std::isfinite(d)) continue;
    sum_sq += d * d;
    ++count;
  }
  return count > 0 ? std::sqrt(sum_sq / static_cast<double>(count) / 6.0) : 0.0;
}

}  // namespace

std::vector<std::size_t> event_rows(const model::Inputs& inputs) {
  std::vector<std::size_t> events;
  const std::vector<double>& u = drive_command(inputs);
  const double jump_limit = drive_jump(u, drive_kind(inputs), k_event_voltage_jump_V, k_event_drive_share);
  for (std::size_t n = 1; n < inputs.t_s.size(); ++n) {
    const bool clutch = inputs.clutch[n] != inputs.clutch[n - 1];
    const double r0 = inputs.r_load_ohm[n - 1];
    const double r1 = inputs.r_load_ohm[n];
    const bool relay = relay_closed(r0) != relay_closed(r1) || (relay_closed(r0) && r0 != r1);
    const bool jump = std::abs(u[n] - u[n - 1]) > jump_limit;
    if (clutch || relay || jump) events.push_back(n);
  }
  return events;
}

std::vector<bool> transient_mask(const model::Inputs& inputs) {
  const std::size_t rows = inputs.t_s.size();
  std::vector<bool> mask(rows, false);
  for (std::size_t e : event_rows(inputs)) {
    for (std::size_t n = e; n < rows && inputs.t_s[n] - inputs.t_s[e] < k_transient_window_s - 1e-9; ++n) {
      mask[n] = true;
    }
  }
  return mask;
}

std::vector<RegimeStat> regime_breakdown(const RegimeContext& context, std::span<const double> residual) {
  MCG_DEMAND(context.inputs != nullptr);
  const model::Inputs& in = *context.inputs;
  MCG_DEMAND(residual.size() == in.t_s.size() && context.rpm_measured.size() == in.t_s.size());
  const std::vector<bool> transient = transient_mask(in);
  const double stuck_rpm = 0.5 * context.rpm_resolution;

  Accumulator all, clutch[3], open, closed, stuck, low, high, forward, reverse, trans, steady;
  for (std::size_t n = 0; n < residual.size(); ++n) {
    const double r = residual[n];
    if (!std::isfinite(r)) continue;
    all.add(r);
    const int c = static_cast<int>(in.clutch[n]);
    if (c >= 0 && c <= 2) clutch[c].add(r);
    (relay_closed(in.r_load_ohm[n]) ? closed : open).add(r);
    const double rpm = context.rpm_measured[n];
    const double speed = std::abs(rpm);
    if (!(speed >= stuck_rpm)) {
      stuck.add(r);
    } else if (speed < context.low_speed) {
      low.add(r);
    } else {
      high.add(r);
    }
    (rpm < 0.0 ? reverse : forward).add(r);
    (transient[n] ? trans : steady).add(r);
  }
  const double total = all.sum_sq;
  return {
      make_stat("all", "all", all, total),
      make_stat("clutch", "state 0", clutch[0], total),
      make_stat("clutch", "state 1", clutch[1], total),
      make_stat("clutch", "state 2", clutch[2], total),
      make_stat("load", "open", open, total),
      make_stat("load", "closed", closed, total),
      make_stat("speed", "stuck", stuck, total),
      make_stat("speed", "< " + context.low_label, low, total),
      make_stat("speed", ">= " + context.low_label, high, total),
      make_stat("direction", "forward", forward, total),
      make_stat("direction", "reverse", reverse, total),
      make_stat("timing", "transient", trans, total),
      make_stat("timing", "steady", steady, total),
  };
}

const std::vector<double>& band_edges_hz() {
  static const std::vector<double> edges = {0.0, 1.0, 10.0, 50.0};
  return edges;
}

std::vector<RegimeStat> band_breakdown(std::span<const double> residual, double dt_s) {
  MCG_DEMAND(dt_s > 0.0);
  const std::vector<double>& edges = band_edges_hz();
  std::vector<Accumulator> bands(edges.size());
  const std::size_t n = residual.size();
  std::size_t finite = 0;
  std::size_t padded = 1;
  while (padded < n) padded *= 2;
  std::vector<double> x(padded, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    if (std::isfinite(residual[k])) {
      x[k] = residual[k];
      ++finite;
    }
  }
  double total = 0.0;
  const double nyquist_hz = 0.5 / dt_s;
  if (n > 0) {
    Eigen::FFT<double> fft;
    std::vector<std::complex<double>> spectrum;
    fft.fwd(spectrum, x);
    // One-sided power: bins 1..padded/2-1 stand for their mirror images too.
    for (std::size_t k = 0; k <= padded / 2; ++k) {
      const double weight = (k == 0 || k == padded / 2) ? 1.0 : 2.0;
      const double power = weight * std::norm(spectrum[k]) / static_cast<double>(padded);
      const double f_hz = static_cast<double>(k) / (static_cast<double>(padded) * dt_s);
      // A band that starts at or above the Nyquist frequency holds nothing: the Nyquist bin
      // closes the band below it.
      std::size_t b = edges.size() - 1;
      while (b > 0 && (f_hz < edges[b] || edges[b] >= nyquist_hz)) --b;
      bands[b].sum_sq += power;
      total += power;
    }
  }
  std::vector<RegimeStat> out;
  for (std::size_t b = 0; b < edges.size(); ++b) {
    RegimeStat s;
    s.group = "band";
    const bool above = b > 0 && edges[b] >= nyquist_hz;
    const double hi = b + 1 < edges.size() ? std::min(edges[b + 1], nyquist_hz) : nyquist_hz;
    s.regime = above ? fmt::format("{:g} Hz and above (beyond Nyquist)", edges[b])
                     : fmt::format("{:g}-{:g} Hz", edges[b], hi);
    s.samples = above ? 0 : finite;
    s.rms = finite > 0 ? std::sqrt(bands[b].sum_sq / static_cast<double>(finite)) : k_nan;
    s.share = total > 0.0 ? bands[b].sum_sq / total : 0.0;
    out.push_back(std::move(s));
  }
  return out;
}

Whiteness whiteness(std::span<const double> residual, std::span<const double> input, std::size_t max_lag,
                    std::size_t first_lag) {
  MCG_DEMAND(residual.size() == input.size() && first_lag >= 1);
  const std::size_t n = residual.size();
  std::vector<double> r(n, 0.0);
  std::vector<double> u(n, 0.0);
  double r_mean = 0.0;
  double u_mean = 0.0;
  std::size_t finite = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (std::isfinite(residual[k]) && std::isfinite(input[k])) {
      r_mean += residual[k];
      u_mean += input[k];
      ++finite;
    }
  }
  Whiteness w;
  w.samples = finite;
  w.first_lag = first_lag;
  if (finite < 2) return w;
  r_mean /= static_cast<double>(finite);
  u_mean /= static_cast<double>(finite);
  double rr = 0.0;
  double uu = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    if (std::isfinite(residual[k]) && std::isfinite(input[k])) {
      r[k] = residual[k] - r_mean;
      u[k] = input[k] - u_mean;
      rr += r[k] * r[k];
      uu += u[k] * u[k];
    }
  }
  w.bound = 2.58 / std::sqrt(static_cast<double>(finite));
  if (rr <= 0.0) return w;
  constexpr double k_z99 = 2.326;
  const auto big_n = static_cast<double>(finite);
  std::size_t auto_lags = 0;
  for (std::size_t lag = first_lag; lag <= max_lag && lag < n; ++lag) {
    double s = 0.0;
    for (std::size_t k = lag; k < n; ++k) s += r[k] * r[k - lag];
    const double rho = s / rr;
    ++auto_lags;
    w.q_auto += big_n * (big_n + 2.0) * rho * rho / (big_n - static_cast<double>(lag));
    if (std::abs(rho) > w.max_auto) {
      w.max_auto = std::abs(rho);
      w.max_auto_lag = lag;
    }
  }
  w.q_auto_limit = auto_lags > 0 ? chi_square_quantile(static_cast<double>(auto_lags), k_z99) : 0.0;
  if (uu > 0.0) {
    const double norm = std::sqrt(rr * uu);
    std::size_t cross_lags = 0;
    for (std::size_t lag = 0; lag <= max_lag && lag < n; ++lag) {
      double s = 0.0;
      for (std::size_t k = lag; k < n; ++k) s += r[k] * u[k - lag];
      const double rho = s / norm;
      ++cross_lags;
      w.q_cross += big_n * rho * rho;
      if (std::abs(rho) > w.max_cross) {
        w.max_cross = std::abs(rho);
        w.max_cross_lag = lag;
      }
    }
    w.q_cross_limit = chi_square_quantile(static_cast<double>(cross_lags), k_z99);
  }
  return w;
}

NoiseFloor rpm_noise_floor(std::span<const double> rpm_measured, const std::vector<bool>& transient,
                           double window_s, double counts_per_rev) {
  MCG_DEMAND(window_s > 0.0 && counts_per_rev > 0.0 && transient.size() == rpm_measured.size());
  const double q = 60.0 / (window_s * counts_per_rev);
  std::size_t moving = 0;
  std::size_t finite = 0;
  for (double y : rpm_measured) {
    if (!std::isfinite(y)) continue;
    ++finite;
    if (std::abs(y) >= 0.5 * q) ++moving;
  }
  NoiseFloor nf;
  if (finite == 0) return nf;
  nf.chain = q * std::sqrt(static_cast<double>(moving) / static_cast<double>(finite) / 6.0);
  nf.data = second_difference_noise(rpm_measured, [&](std::size_t n) {
    return !transient[n] && std::abs(rpm_measured[n]) >= 0.5 * q;
  });
  return nf;
}

NoiseFloor current_noise_floor(std::span<const double> i_measured, const std::vector<bool>& transient,
                               double adc_step_A, double sigma_A) {
  MCG_DEMAND(transient.size() == i_measured.size());
  NoiseFloor nf;
  nf.chain = std::sqrt(sigma_A * sigma_A + adc_step_A * adc_step_A / 12.0);
  nf.data = second_difference_noise(i_measured, [&](std::size_t n) { return !transient[n]; });
  return nf;
}

double chi_square_quantile(double dof, double z_p) {
  MCG_DEMAND(dof > 0.0);
  const double a = 2.0 / (9.0 * dof);
  const double c = 1.0 - a + z_p * std::sqrt(a);
  return dof * c * c * c;
}

}  // namespace mcg::fit
