// Emulation of the board's digital controller and the closed loop around the plant.
#include "sim/controller.hpp"

#include <algorithm>
#include "common/demand.hpp"
#include <cmath>

#include "common/error.hpp"
#include "config/ini.hpp"

namespace mcg::sim {

ControllerState::ControllerState(const Controller& controller)
    : m_c(controller), m_e(controller.b.size(), 0.0), m_y(controller.a.size() > 1 ? controller.a.size() - 1 : 0, 0.0) {
  MCG_DEMAND(!m_c.b.empty() && !m_c.a.empty() && m_c.a[0] != 0.0);
}

double ControllerState::step(double error_rpm) {
  std::rotate(m_e.rbegin(), m_e.rbegin() + 1, m_e.rend());
  m_e[0] = m_c.input_scale * error_rpm;
  double acc = 0.0;
  for (std::size_t k = 0; k < m_e.size(); ++k) acc += m_c.b[k] * m_e[k];
  for (std::size_t k = 0; k < m_y.size(); ++k) acc -= m_c.a[k + 1] * m_y[k];
  double y = acc / m_c.a[0];
  if (m_c.round_output) y = std::round(y);
  y = std::clamp(y, -m_c.duty_full_scale, m_c.duty_full_scale);
  if (!m_y.empty()) {
    std::rotate(m_y.rbegin(), m_y.rbegin() + 1, m_y.rend());
    m_y[0] = y;
  }
  double duty = y / m_c.duty_full_scale;
  if (m_c.duty_resolution > 0.0) duty = std::round(duty / m_c.duty_resolution) * m_c.duty_resolution;
  return std::clamp(duty, -1.0, 1.0);
}

double WindowCounter::push(double t, double theta) {
  if (m_hist.empty()) m_hist.emplace_back(t, theta);
  const double tol = 1e-9 + 1e-6 * m_e.window_s;
  const double t_back = t - m_e.window_s;
  m_hist.emplace_back(t, theta);
  // Keep one sample at or before t - W (the oldest needed), drop older ones.
  std::size_t drop = 0;
  while (drop + 1 < m_hist.size() && m_hist[drop + 1].first <= t_back + tol) ++drop;
  if (drop > 0) m_hist.erase(m_hist.begin(), m_hist.begin() + static_cast<std::ptrdiff_t>(drop));
  double theta_back = m_hist.front().second;
  const auto& [t0, th0] = m_hist.front();
  if (t_back > t0 + tol && m_hist.size() > 1) {
    const auto& [t1, th1] = m_hist[1];
    theta_back = th0 + (t_back - t0) / (t1 - t0) * (th1 - th0);
  }
  return (encoder_count(theta, m_e.counts_per_rev) - encoder_count(theta_back, m_e.counts_per_rev)) *
         m_e.rpm_per_count();
}

ClosedLoop::ClosedLoop(const model::Model& model, const Controller& controller, const CountEstimator& estimator,
                       const model::SimOptions& options, int initial_clutch)
    : m_plant(model, options, initial_clutch),
      m_ctl(controller),
      m_counter(estimator),
      m_dt_s(controller.dt_s),
      m_tol_s(1e-9 * controller.dt_s),
      m_supply_V(model.params.supply_V) {}

void ClosedLoop::tick(double t_s, double rpm_cmd) {
  const double rpm = m_counter.push(t_s, m_plant.state().theta_rad);
  m_duty = m_ctl.step(rpm_cmd - rpm);
  ++m_tick;
}

void ClosedLoop::row(double t_s, double rpm_cmd, int clutch, double r_load_ohm) {
  if (!m_started) {
    m_started = true;
    m_t0_s = t_s;
  } else {
    MCG_DEMAND(t_s > m_t_s);
    // The previous row's interval: step to each tick inside it, tick there with its command.
    double t = m_t_s;
    bool first = true;
    while (true) {
      if (!first && std::abs(tick_time(m_tick) - t) <= m_tol_s) tick(t, m_rpm_cmd);
      first = false;
      const double t_next = std::min(t_s, tick_time(m_tick));
      if (t_next - t <= m_tol_s) {
        if (t_s - t <= m_tol_s) break;
        continue;
      }
      model::Drive drive = m_drive;
      drive.v_V = m_duty * m_supply_V;
      m_plant.step(t_next - t, drive);
      t = t_next;
      if (t_s - t <= m_tol_s) break;
    }
  }
  if (std::abs(tick_time(m_tick) - t_s) <= m_tol_s) tick(t_s, rpm_cmd);
  m_t_s = t_s;
  m_rpm_cmd = rpm_cmd;
  m_drive = model::Drive{0.0, clutch, r_load_ohm};
}

ClosedLoopOutputs simulate_closed_loop(const model::Model& model, const Controller& controller,
                                       const CountEstimator& estimator, const ClosedLoopInputs& in,
                                       const model::SimOptions& options) {
  const std::size_t n = in.t_s.size();
  MCG_DEMAND(in.rpm_cmd.size() == n && in.clutch.size() == n && in.r_load_ohm.size() == n);
  ClosedLoopOutputs out;
  out.plant.resize(n);
  out.duty.assign(n, 0.0);
  out.v_V.assign(n, 0.0);
  if (n == 0) return out;
  ClosedLoop loop(model, controller, estimator, options, static_cast<int>(in.clutch[0]));
  for (std::size_t row = 0; row < n; ++row) {
    loop.row(in.t_s[row], in.rpm_cmd[row], static_cast<int>(in.clutch[row]), in.r_load_ohm[row]);
    out.plant.store(row, loop.state());
    out.duty[row] = loop.duty();
    out.v_V[row] = loop.duty() * model.params.supply_V;
  }
  return out;
}

}  // namespace mcg::sim
