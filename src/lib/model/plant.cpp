// The plant integrator: exponential RK4 between events, stick-slip and clutch events located
// inside a step.
//
// The continuous state is y = [i_m, i_g, w_m, w_g, theta_m, theta_g, x_m, x_g] (x: the windings'
// extra states). The effects reach it only through the typed hooks of model/effects/compiled.hpp.
// The discrete
// mode is the clutch coupling (none, rigid, spring, slipping plates), for each body whether it is
// stuck and, if moving, its direction. Each armature circuit's stiff linear part,
// di/dt = -(R/L) i + ..., is stepped exactly (Cox and Matthews' ETDRK4: the rest of the
// right-hand side by RK4's stages, the decay by its exponential), so the step is not bound by
// L/R; the other states take classical RK4 (the scheme's limit at R/L = 0). Within a step the
// direction is held, so the right-hand side is smooth and the scheme keeps its order; a speed
// reaching zero, a stuck body's drive torque
// leaving the static band and the slip speed of the clutch plates reaching zero are located
// in the step (cubic Hermite interpolation of the speed, secant on the torque), the step is
// redone up to the event, the mode switches and integration continues.
//
// The integrator is a template on its number type: double for the simulation, Dual
// (model/dual.hpp) for its sensitivities to the parameters (model/sensitivity.hpp). The
// branches follow the values; the event times carry their derivatives (hermite_root, the
// breakaway fractions), so the sensitivities are those of the run the values take.
#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <numbers>
#include <optional>
#include <type_traits>

#include "common/checked.hpp"
#include "common/demand.hpp"
#include "common/error.hpp"
#include "model/effects/compiled.hpp"
#include "model/model.hpp"

namespace mcg::model {

namespace {

constexpr int k_states = 8;
enum : std::size_t { I_M, I_G, W_M, W_G, TH_M, TH_G, X_M, X_G };

/// Circuits faster than this R/L, 1/s (the generator's R + r_load, the motor's R + series),
/// are solved as algebraic: the current follows within 50 us, far below any mechanical time
/// constant, and a step resolving it would be microseconds.
constexpr double k_quasi_static_rate = 2e4;
/// Events handled inside one integration step before the step is accepted as is.
constexpr int k_max_events_per_step = 16;
/// A torque ripple's largest phase advance in one step, rad (ripple_step_limit). RK4's stages
/// sample it 1 rad apart; near pi a step they sample it alike step after step, and the ripple
/// aliases into a steady torque (the rig's motor with a 40-per-revolution ripple at 330 rad/s:
/// 6.2 rpm RMS off at 3.0 rad a step, 0.023 rpm at 1.9).
constexpr double k_phase_per_step = 2.0;
/// SimOptions::circuit_bound: a circuit whose L/R is under this share of the largest step, or
/// of the interval between rows where that is longer, bounds the step by the motor's
/// mechanical time constant over k_steps_per_tau_m; a slower one by half its L/R.
constexpr double k_fast_circuit_share = 0.25;
constexpr double k_steps_per_tau_m = 16.0;
/// The regularised stick's breakaway (SimOptions::smooth_stick): a stuck motor breaks away at
/// the rate exp((|T| - Ts) / (k_stick_width Ts)) / k_stick_time_s once its drive torque T
/// exceeds the Coulomb level, so at Ts after 10 ms, 5 % below it after 1.5 s, 5 % above it
/// within 0.1 ms. On a ramp of rate a it breaks at Ts + sigma ln(a tau / sigma) (sigma = 1 %
/// of Ts, tau = 10 ms): 0.011 Ts early on a ramp that reaches Ts in 3 s.
constexpr double k_stick_width = 0.01;
constexpr double k_stick_time_s = 0.01;

enum class Coupling { none, rigid, spring, slip };

using std::abs;
using std::exp;
using std::expm1;
using std::sqrt;
using std::tanh;

/// x limited to [lo, hi], its derivatives with it inside and 0 on a limit (a breakaway hazard
/// past 1 at once, 1/inf = 0, is at the step's start whatever its derivatives).
template <class S>
S clamp(const S& x, double lo, double hi) {
  return x <= lo ? S(lo) : (x >= hi ? S(hi) : x);
}

template <class S>
int sign_of(const S& x) {
  return x > 0.0 ? 1 : (x < 0.0 ? -1 : 0);
}

}  // namespace

template <class S, class C>
class PlantCore {
 public:
  using Vec = std::array<S, k_states>;
  using Friction = BasicFriction<S>;

  PlantCore(C compiled, const SimOptions& options, int initial_clutch)
      : m_c(std::move(compiled)), m_opt(options) {
    m_y.fill(0.0);
    m_y[X_M] = m_c.winding.x0;
    m_y[X_G] = m_c.winding.x0;
    m_clutch = initial_clutch;
    m_motor_quasi = (m_c.p.motor.R_ohm + m_c.circuit.R_series_ohm) / m_c.p.motor.L_H > k_quasi_static_rate;
    m_t_engage = -std::numeric_limits<double>::infinity();
    if (m_clutch == 2) {
      m_coupling = spring() ? Coupling::spring : Coupling::rigid;
    }
    set_bridge();
    update_gen_mode();
  }

  void step(double dt, const Drive& drive, const S& i_cmd_A) {
    MCG_DEMAND(dt > 0.0);
    MCG_DEMAND(drive.clutch >= 0 && drive.clutch <= 2);
    MCG_DEMAND(drive.r_load_ohm >= 0.0);
    set_clutch(drive.clutch);
    set_load(drive.r_load_ohm);
    m_row_s = dt;
    const S t_end = m_t + dt;
    if (m_c.delay_s > 0.0) {
      m_queue.push_back({m_t + m_c.delay_s, drive.v_V, i_cmd_A});
    } else {
      command(drive.v_V, i_cmd_A);
    }
    constexpr double k_time_eps = 1e-12;
    while (m_t < t_end - k_time_eps) {
      while (!m_queue.empty() && m_queue.front().t_s <= m_t + k_time_eps) take_queued();
      S seg_end = t_end;
      if (!m_queue.empty() && m_queue.front().t_s < t_end - k_time_eps) seg_end = m_queue.front().t_s;
      integrate(seg_end - m_t);
      m_t = seg_end;
    }
    m_t = t_end;
    while (!m_queue.empty() && m_queue.front().t_s <= m_t + k_time_eps) take_queued();
  }

  void start_at(S w) {
    MCG_DEMAND(m_t == 0.0 && std::isfinite(value_of(w)));
    m_y[W_M] = w;
    m_stuck_m = (w == 0.0);
    m_dir_m = sign_of(w);
    if (m_clutch == 2) {
      m_y[W_G] = w;
      m_stuck_g = (w == 0.0);
      m_dir_g = sign_of(w);
    }
    if (gen_quasi_static()) m_y[I_G] = gen_current(m_y);
  }

  BasicState<S> state() const {
    BasicState<S> s;
    s.t_s = value_of(m_t);
    s.omega_rad_s = m_y[W_M];
    s.omega_gen_rad_s = m_y[W_G];
    s.theta_rad = m_y[TH_M];
    s.theta_gen_rad = m_y[TH_G];
    s.i_A = motor_current(m_y);
    s.i_gen_A = gen_current(m_y);
    if (!gen_present()) {
      s.v_gen_V = 0.0;
    } else if (std::isinf(m_r_load)) {
      s.v_gen_V = m_c.p.generator.Ke_V_s_rad * m_y[W_G];
    } else {
      s.v_gen_V = m_r_load * s.i_gen_A;
    }
    S d = 0.0;
    const S v_b = bridge(d);
    if (current_driven()) {
      s.v_applied_V = motor_resistance(m_y) * s.i_A + m_c.p.motor.Ke_V_s_rad * m_y[W_M];
      if (m_c.circuit.V_sat_V > 0.0) s.v_applied_V += m_c.circuit.drop(s.i_A);
    } else {
      s.v_applied_V = v_b - (m_c.circuit.R_series_ohm + abs(d) * m_c.circuit.R_duty_ohm) * s.i_A +
                      (1.0 - m_emf_share) * m_c.p.motor.Ke_V_s_rad * m_y[W_M];
    }
    s.temp_rise_K = m_y[X_M];
    s.clutch = m_clutch;
    s.stuck = m_stuck_m;
    return s;
  }

  double time() const { return value_of(m_t); }

 private:
  bool gen_present() const { return m_clutch != 0; }
  bool gen_circuit() const { return m_gen_circuit; }
  bool gen_quasi_static() const { return m_gen_quasi; }
  /// Caches whether the generator circuit is closed, and whether it is fast enough to be
  /// solved as algebraic; called whenever the clutch state or the load changes.
  void update_gen_mode() {
    m_gen_circuit = gen_present() && std::isfinite(m_r_load);
    m_gen_quasi =
        m_gen_circuit && (m_c.p.generator.R_ohm + m_r_load) / m_c.p.generator.L_H > k_quasi_static_rate;
    update_rates();
  }
  bool rigid() const { return m_coupling == Coupling::rigid; }
  bool spring() const { return m_c.coupling.spring_k_Nm_rad > 0.0; }
  bool winding_states() const { return m_c.winding.rate != nullptr; }
  /// An ideal current loop holds the motor current (Drive::i_cmd_A): no circuit to integrate.
  bool current_driven() const { return !std::isnan(value_of(m_i_cmd)); }
  /// Takes a drive's command; the motor current state follows a current loop's command.
  void command(double v_V, const S& i_cmd_A) {
    m_v = v_V;
    m_i_cmd = i_cmd_A;
    if (current_driven()) m_y[I_M] = m_i_cmd;
    set_bridge();
  }

  /// Applies the first delayed command at m_t. Its time may equal m_t in value (a delay a
  /// multiple of the rows' interval) but not in its derivatives: the switch then moves the
  /// state by (f_before - f_after) d(t_cmd - m_t), the jump of a switch time's sensitivity
  /// (inside an interval the steps' lengths carry it).
  void take_queued() {
    const Queued q = m_queue.front();
    m_queue.pop_front();
    if constexpr (std::is_same_v<S, Dual>) {
      const Dual shift = q.t_s - m_t;
      if (!same_derivatives(shift, Dual(0.0))) {
        Vec before, after;
        deriv(m_y, m_t, before);
        command(q.v_V, q.i_cmd_A);
        deriv(m_y, m_t, after);
        for (std::size_t k = 0; k < k_states; ++k) {
          m_y[k].d += (before[k].v - after[k].v) * shift.d;
        }
        return;
      }
    }
    command(q.v_V, q.i_cmd_A);
  }

  /// The bridge at the command in force, once per command rather than at every stage: its
  /// duty d' (m_duty), its output d' supply_V (m_v_bridge), the back-emf's share of the period
  /// (m_emf_share), the motor circuit's resistance R + R_series + |d'| R_duty without the
  /// windings' states (m_R_bridge_ohm), and the rates.
  void set_bridge() {
    const S supply = m_c.p.supply_V;
    m_duty = m_c.circuit.duty(clamp(m_v / supply, -1.0, 1.0));
    m_v_bridge = m_duty * supply;
    m_emf_share = m_c.circuit.emf_share(m_duty);
    m_R_bridge_ohm = m_c.p.motor.R_ohm + m_c.circuit.R_series_ohm + abs(m_duty) * m_c.circuit.R_duty_ohm;
    update_rates();
  }

  /// Bridge output before the current-dependent drops: d' supply_V; d' is returned.
  S bridge(S& d_out) const {
    d_out = m_duty;
    return m_v_bridge;
  }

  S gen_resistance(const Vec& y) const {
    const S R = m_c.p.generator.R_ohm;
    return winding_states() ? R * (1.0 + m_c.winding.R_per_x * y[X_G]) : R;
  }

  /// The current of a circuit fast enough to be algebraic: R i + V_sat tanh(i / i_sat) = emf.
  /// g(i) rises monotonically: safeguarded Newton in the bracket [-|emf|/R, |emf|/R].
  S algebraic_current(S emf, S R) const {
    const S V_sat = m_c.circuit.V_sat_V, i_sat = m_c.circuit.i_sat_A;
    if (V_sat <= 0.0) return emf / R;
    S lo = -abs(emf) / R;
    S hi = abs(emf) / R;
    S i = emf / (R + V_sat / i_sat);
    for (int it = 0; it < 60 && hi - lo > 1e-15; ++it) {
      const S th = tanh(i / i_sat);
      const S g = R * i + V_sat * th - emf;
      if (g > 0.0) {
        hi = i;
      } else {
        lo = i;
      }
      const S slope = R + V_sat / i_sat * (1.0 - th * th);
      S next = i - g / slope;
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      if (abs(next - i) <= 1e-14 * (1.0 + abs(i))) return next;
      i = next;
    }
    return i;
  }

  /// The generator current: the state, or the algebraic solution of
  /// Ke w_g = (R + r_load) i + drop(i) for a fast circuit.
  S gen_current(const Vec& y) const {
    if (!gen_circuit()) return 0.0;
    if (!gen_quasi_static()) return y[I_G];
    return algebraic_current(m_c.p.generator.Ke_V_s_rad * y[W_G], gen_resistance(y) + m_r_load);
  }

  /// The motor circuit's resistance at the bridge's duty d': winding (with its state), series,
  /// duty share.
  S motor_resistance(const Vec& y) const {
    if (!winding_states()) return m_R_bridge_ohm;
    return m_c.p.motor.R_ohm * (1.0 + m_c.winding.R_per_x * y[X_M]) + m_c.circuit.R_series_ohm +
           abs(m_duty) * m_c.circuit.R_duty_ohm;
  }

  /// The motor current: the state, or for a motor whose electrical time constant is far
  /// below the steps (a low-inductance gearmotor: L/R under 50 us) the algebraic solution of
  /// v_b - Ke w = R i + drop(i), so that no step has to resolve it.
  S motor_current(const Vec& y) const {
    if (current_driven()) return m_i_cmd;
    if (!m_motor_quasi) return y[I_M];
    S d = 0.0;
    const S v_b = bridge(d);
    return algebraic_current(v_b - m_emf_share * m_c.p.motor.Ke_V_s_rad * y[W_M], motor_resistance(y));
  }

  /// Capacity of the clutch plates at time t (CouplingTerms::capacity).
  S capacity(S t) const {
    const S age = t - m_t_engage;
    if (age <= 0.0) return 0.0;
    return m_c.coupling.capacity(m_c.coupling.capacity_k, age);
  }

  const Friction& motor_friction() const { return m_c.motor_side[static_cast<std::size_t>(m_clutch)]; }

  /// Torques on the bodies other than friction: motor body (or the rigid pair) and generator body.
  void drive_torques(const Vec& y, S t, S& Tm, S& Tg) const { drive_torques(y, t, m_coupling, Tm, Tg); }
  void drive_torques(const Vec& y, S t, Coupling coupling, S& Tm, S& Tg) const {
    drive_torques(y, t, coupling, motor_current(y), gen_current(y), Tm, Tg);
  }
  /// The same with the currents i_m, i_g at y already known (deriv has them; an algebraic
  /// circuit's current is a Newton solve).
  void drive_torques(const Vec& y, S t, Coupling coupling, S i_m, S i_g, S& Tm, S& Tg) const {
    Tm = m_c.p.motor.Kt_Nm_A * i_m;
    if (!m_c.motor_torque.empty()) Tm += m_c.extra_motor_torque(y[TH_M], y[W_M], i_m, t);
    Tg = -m_c.p.generator.Kt_Nm_A * i_g;
    switch (coupling) {
      case Coupling::none:
        break;
      case Coupling::rigid:
        Tm += Tg;
        Tg = 0.0;
        break;
      case Coupling::spring: {
        const S Ts =
            m_c.coupling.spring_k_Nm_rad * (y[TH_M] - y[TH_G] - m_phi0) + m_c.c_spring * (y[W_M] - y[W_G]);
        Tm -= Ts;
        Tg += Ts;
        break;
      }
      case Coupling::slip: {
        const S Tcl = capacity(t) * m_slip_dir;
        Tm -= Tcl;
        Tg += Tcl;
        break;
      }
    }
  }

  // Inlined into every stage: four calls a step, where the call itself cost a sixth of the body.
  [[gnu::always_inline]] void deriv(const Vec& y, S t, Vec& dy) const {
    S d = 0.0;
    const S v_b = bridge(d);
    const BasicMachine<S>& mm = m_c.p.motor;
    const BasicMachine<S>& mg = m_c.p.generator;
    const S Rm = motor_resistance(y);
    const S i_m = motor_current(y);
    const S load_Nm = abs(mm.Kt_Nm_A * i_m);
    if (m_motor_quasi || current_driven()) {
      dy[I_M] = 0.0;
    } else {
      S vm = v_b - Rm * i_m - m_emf_share * mm.Ke_V_s_rad * y[W_M];
      if (m_c.circuit.V_sat_V > 0.0) vm -= m_c.circuit.drop(i_m);
      dy[I_M] = vm / mm.L_H;
    }
    const S i_g = gen_current(y);
    dy[I_G] = 0.0;
    if (gen_circuit() && !gen_quasi_static()) {
      S vg = mg.Ke_V_s_rad * y[W_G] - (gen_resistance(y) + m_r_load) * y[I_G];
      if (m_c.circuit.V_sat_V > 0.0) vg -= m_c.circuit.drop(y[I_G]);
      dy[I_G] = vg / mg.L_H;
    }
    S Tm = 0.0, Tg = 0.0;
    drive_torques(y, t, m_coupling, i_m, i_g, Tm, Tg);
    if (rigid()) {
      const S a =
          m_stuck_m ? 0.0 : (Tm - m_dir_m * m_c.kinetic(m_c.rigid, m_dir_m * y[W_M], load_Nm)) / m_c.J_total;
      dy[W_M] = a;
      dy[W_G] = a;
    } else {
      dy[W_M] = m_stuck_m
                    ? 0.0
                    : (Tm - m_dir_m * m_c.kinetic(motor_friction(), m_dir_m * y[W_M], load_Nm)) / mm.J_kg_m2;
      dy[W_G] = (m_stuck_g || !gen_present())
                    ? 0.0
                    : (Tg - m_dir_g * m_c.kinetic(m_c.gen, m_dir_g * y[W_G])) / mg.J_kg_m2;
    }
    dy[TH_M] = y[W_M];
    dy[TH_G] = y[W_G];
    if (winding_states()) {
      const auto& w = m_c.winding;
      dy[X_M] =
          w.rate(w.k, i_m * i_m * (Rm - m_c.circuit.R_series_ohm - abs(d) * m_c.circuit.R_duty_ohm), y[X_M]);
      dy[X_G] = w.rate(w.k, i_g * i_g * gen_resistance(y), y[X_G]);
    } else {
      dy[X_M] = 0.0;
      dy[X_G] = 0.0;
    }
  }

  Vec rk4(const Vec& y0, S t0, S h, const Vec& k1) const {
    Vec k2, k3, k4, tmp;
    for (std::size_t j = 0; j < k_states; ++j) tmp[j] = y0[j] + 0.5 * h * k1[j];
    deriv(tmp, t0 + 0.5 * h, k2);
    for (std::size_t j = 0; j < k_states; ++j) tmp[j] = y0[j] + 0.5 * h * k2[j];
    deriv(tmp, t0 + 0.5 * h, k3);
    for (std::size_t j = 0; j < k_states; ++j) tmp[j] = y0[j] + h * k3[j];
    deriv(tmp, t0 + h, k4);
    Vec y1;
    for (std::size_t j = 0; j < k_states; ++j) {
      y1[j] = y0[j] + h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
    }
    return y1;
  }

  /// Decay rates lambda = -R/L, 1/s, of the armature circuits integrated as states (0 for every
  /// other state): the stiff linear part the exponential step takes exactly. A saturating drop
  /// adds its local slope at each step's start (drop_rate). The windings' states stay in the
  /// rest of the right-hand side. Kept in m_lam, set whenever the command, the clutch or the
  /// load changes.
  void update_rates() {
    m_lam.fill(0.0);
    if (!m_motor_quasi && !current_driven()) m_lam[I_M] = -m_R_bridge_ohm / m_c.p.motor.L_H;
    if (gen_circuit() && !gen_quasi_static())
      m_lam[I_G] = -(m_c.p.generator.R_ohm + m_r_load) / m_c.p.generator.L_H;
  }

  /// The saturating drop's slope at current i over the circuit's inductance L, 1/s:
  /// d/di [V_sat tanh(i / i_sat)] / L = V_sat / (i_sat L) (1 - tanh^2(i / i_sat)); 100 ohm per
  /// volt of a brush drop near zero current, exactly 0 far from it.
  S drop_rate(S i_A, S L_H) const {
    const S th = tanh(i_A / m_c.circuit.i_sat_A);
    return m_c.circuit.V_sat_V / (m_c.circuit.i_sat_A * L_H) * (1.0 - th * th);
  }

  /// The coefficients of one step of h for one circuit of rate lambda (z = lambda h): the
  /// half- and full-step decays and the weights of the stages (Cox and Matthews 2002),
  /// phi_k(z) = sum_n z^n / (n + k)! by its series near 0 where the closed forms cancel.
  struct ExpCoef {
    S lambda = 0.0, h = 0.0;
    S e_half = 1.0, e_full = 1.0, stage = 0.0, w1 = 0.0, w2 = 0.0, w3 = 0.0;
  };
  static void phi(S z, S& p1, S& p2, S& p3) {
    if (abs(z) < 0.2) {
      p1 = p2 = p3 = 0.0;
      S term = 1.0;  // z^n / n!
      for (int n = 0; n < 14; ++n) {
        p1 += term / ((n + 1.0));
        p2 += term / ((n + 1.0) * (n + 2.0));
        p3 += term / ((n + 1.0) * (n + 2.0) * (n + 3.0));
        term *= z / (n + 1.0);
      }
      return;
    }
    const S em1 = expm1(z);
    p1 = em1 / z;
    p2 = (em1 - z) / (z * z);
    p3 = (em1 - z - 0.5 * z * z) / (z * z * z);
  }
  /// Coefficients kept per circuit: a dead time splits every row into two steps of different
  /// lengths, and the step bound splits each again, so a few lengths recur in turn.
  static constexpr std::size_t k_coef_memo = 4;
  struct CoefMemo {
    std::array<ExpCoef, k_coef_memo> coef{};
    std::size_t last = 0;  ///< the entry computed or found last
    std::size_t next = 0;  ///< the entry the next computation overwrites
  };
  const ExpCoef& exp_coef(std::size_t slot, S lambda, S h) const {
    CoefMemo& memo = m_coef[slot];
    // Rows at decimal times differ in the last bits of their spacing: one step's coefficients
    // serve the next within a relative 1e-9 of h (a change of order 1e-9 in the decay).
    // On dual numbers an entry serves only the same derivatives; a step the values would serve
    // by the last entry takes that entry's length with its own derivatives, so the values stay
    // those of the plain simulation.
    const ExpCoef& last = memo.coef[memo.last];
    S h_used = h;
    if (last.lambda == lambda && std::abs(value_of(last.h) - value_of(h)) <= 1e-9 * value_of(h)) {
      if (identical(last.lambda, lambda) && same_derivatives(last.h, h)) return last;
      h_used = with_value(h, value_of(last.h));
    } else {
      // Any other entry serves only a step of exactly its length, so that the coefficients are
      // the ones computed afresh would be.
      for (std::size_t k = 0; k < k_coef_memo; ++k) {
        if (identical(memo.coef[k].lambda, lambda) && identical(memo.coef[k].h, h)) {
          memo.last = k;
          return memo.coef[k];
        }
      }
    }
    memo.last = memo.next;
    memo.next = (memo.next + 1) % k_coef_memo;
    ExpCoef& c = memo.coef[memo.last];
    c.lambda = lambda;
    c.h = h_used;
    const S z = lambda * h_used;
    S p1 = 0.0, p2 = 0.0, p3 = 0.0;
    phi(0.5 * z, p1, p2, p3);
    c.e_half = exp(0.5 * z);
    c.stage = 0.5 * h_used * p1;
    phi(z, p1, p2, p3);
    c.e_full = exp(z);
    c.w1 = h_used * (p1 - 3.0 * p2 + 4.0 * p3);
    c.w2 = h_used * (p2 - 2.0 * p3);
    c.w3 = h_used * (4.0 * p3 - p2);
    return c;
  }

  /// One step of h from y0 (k1 = f(y0)): classical RK4 for the states of rate 0, ETDRK4 for
  /// the circuits, y' = lambda y + N(y): a = e^(z/2) y0 + h/2 phi1(z/2) N(y0),
  /// b = e^(z/2) y0 + h/2 phi1(z/2) N(a), c = e^(z/2) a + h/2 phi1(z/2) (2 N(b) - N(y0)),
  /// y1 = e^z y0 + h (phi1 - 3 phi2 + 4 phi3) N(y0) + 2 h (phi2 - 2 phi3) (N(a) + N(b))
  ///      + h (4 phi3 - phi2) N(c); exact for a constant N, RK4 at lambda = 0.
  /// Under a saturating drop lambda is the circuit's whole slope at y0, -(R + drop'(i0)) / L
  /// (an exponential Rosenbrock linearisation): the stiff mode near zero current decays
  /// exactly at any step, with no switch, so the step is smooth in every parameter.
  /// The circuits (I_M, I_G) come first in the state and take the exponential step where their
  /// rate is not 0; the loops over the other states have no branch.
  Vec step_once(const Vec& y0, S t0, S h, const Vec& k1) const {
    Vec lam = m_lam;
    if (m_c.circuit.V_sat_V > 0.0) {
      if (lam[I_M] != 0.0) lam[I_M] -= drop_rate(y0[I_M], m_c.p.motor.L_H);
      if (lam[I_G] != 0.0) lam[I_G] -= drop_rate(y0[I_G], m_c.p.generator.L_H);
    }
    if (lam[I_M] == 0.0 && lam[I_G] == 0.0) return rk4(y0, t0, h, k1);
    constexpr std::size_t k_circuits = 2;
    std::array<const ExpCoef*, k_circuits> coef{};
    for (std::size_t j : {I_M, I_G}) coef[j] = lam[j] != 0.0 ? &exp_coef(j, lam[j], h) : nullptr;
    Vec n1, n2, n3, n4, a, b, c;
    for (std::size_t j = 0; j < k_states; ++j) n1[j] = k1[j] - lam[j] * y0[j];
    for (std::size_t j = 0; j < k_circuits; ++j) {
      a[j] = coef[j] ? coef[j]->e_half * y0[j] + coef[j]->stage * n1[j] : y0[j] + 0.5 * h * k1[j];
    }
    for (std::size_t j = k_circuits; j < k_states; ++j) a[j] = y0[j] + 0.5 * h * k1[j];
    deriv(a, t0 + 0.5 * h, n2);
    for (std::size_t j = 0; j < k_states; ++j) n2[j] -= lam[j] * a[j];
    for (std::size_t j = 0; j < k_circuits; ++j) {
      b[j] = coef[j] ? coef[j]->e_half * y0[j] + coef[j]->stage * n2[j] : y0[j] + 0.5 * h * n2[j];
    }
    for (std::size_t j = k_circuits; j < k_states; ++j) b[j] = y0[j] + 0.5 * h * n2[j];
    deriv(b, t0 + 0.5 * h, n3);
    for (std::size_t j = 0; j < k_states; ++j) n3[j] -= lam[j] * b[j];
    for (std::size_t j = 0; j < k_circuits; ++j) {
      c[j] = coef[j] ? coef[j]->e_half * a[j] + coef[j]->stage * (2.0 * n3[j] - n1[j]) : y0[j] + h * n3[j];
    }
    for (std::size_t j = k_circuits; j < k_states; ++j) c[j] = y0[j] + h * n3[j];
    deriv(c, t0 + h, n4);
    Vec y1;
    for (std::size_t j = 0; j < k_circuits; ++j) {
      if (coef[j]) {
        const ExpCoef& e = *coef[j];
        n4[j] -= lam[j] * c[j];
        y1[j] = e.e_full * y0[j] + e.w1 * n1[j] + 2.0 * e.w2 * (n2[j] + n3[j]) + e.w3 * n4[j];
      } else {
        y1[j] = y0[j] + h / 6.0 * (n1[j] + 2.0 * n2[j] + 2.0 * n3[j] + n4[j]);
      }
    }
    for (std::size_t j = k_circuits; j < k_states; ++j) {
      y1[j] = y0[j] + h / 6.0 * (n1[j] + 2.0 * n2[j] + 2.0 * n3[j] + n4[j]);
    }
    return y1;
  }

  /// Largest step for accuracy: a fraction of the spring's time scale, and of the electrical
  /// time constants where asked (SimOptions::circuit_bound) or under a saturating drop (whose
  /// slope the step takes at its start only). The bound holds R/L without the drop: it depends
  /// on the parameters alone, not on the state (integrate narrows it with the state).
  double step_limit() const {
    double h = m_opt.max_step_s;
    const BasicMachine<S>& mm = m_c.p.motor;
    // A torque of the shaft angle varies within a millisecond at speed: a ripple's step follows
    // the speed (integrate, ripple_step_limit); a term of unknown shape (a discrepancy term)
    // keeps the electrical bound, which resolves the angle as it always did.
    const bool electrical_bound =
        m_c.circuit.V_sat_V > 0.0 || std::any_of(m_c.motor_torque.begin(), m_c.motor_torque.end(),
                                                 [](const auto& term) { return term.angle_rate < 0.0; });
    // A circuit's bound (SimOptions::circuit_bound): half its L/R where its decay spans steps
    // or a good part of a row; where it is over within a quarter of both, a share of the
    // motor's mechanical time constant instead.
    const double resolved_s = k_fast_circuit_share * std::max(m_opt.max_step_s, m_row_s);
    const auto circuit = [&](double tau_s, double tau_m_s) {
      if (electrical_bound || (m_opt.circuit_bound && tau_s > resolved_s)) {
        h = std::min(h, 0.5 * tau_s);
      } else if (m_opt.circuit_bound) {
        h = std::min(h, tau_m_s / k_steps_per_tau_m);
      }
    };
    const double R_motor_ohm = value_of(mm.R_ohm + m_c.circuit.R_series_ohm + m_c.circuit.R_duty_ohm);
    const double tau_m_s = value_of(mm.J_kg_m2) * R_motor_ohm / value_of(mm.Kt_Nm_A * mm.Ke_V_s_rad);
    if (!m_motor_quasi && !current_driven()) circuit(value_of(mm.L_H) / R_motor_ohm, tau_m_s);
    if (gen_circuit() && !gen_quasi_static()) {
      circuit(value_of(m_c.p.generator.L_H) / (value_of(m_c.p.generator.R_ohm) + m_r_load), tau_m_s);
    }
    if (spring() && m_coupling == Coupling::spring) {
      const double inv_J = value_of(1.0 / m_c.p.motor.J_kg_m2 + 1.0 / m_c.p.generator.J_kg_m2);
      const double w_n = std::sqrt(value_of(m_c.coupling.spring_k_Nm_rad) * inv_J);
      h = std::min(h, 0.3 / (w_n + value_of(m_c.c_spring) * inv_J));
    }
    return h;
  }

  /// Integrates over len: evenly, or under a drop or a ripple in steps that follow the state.
  void integrate(const S& len) {
    const double h_lim = step_limit();
    const bool drop = m_c.circuit.V_sat_V > 0.0 && drop_circuits();
    const double ripple = ripple_rate();
    if (drop || ripple > 0.0) {
      // The drop's slope changes by up to V_sat / i_sat where the current crosses zero, and a
      // ripple's phase moves with the speed: the step follows the state there
      // (drop_step_limit, ripple_step_limit), and the interval's last step takes what is
      // left. So the steps move continuously with the parameters: a step more appears at
      // length 0, where evenly spread steps would all jump at once.
      S t = m_t;
      S remaining = len;
      while (remaining > 1e-15) {
        Vec k1;
        deriv(m_y, t, k1);
        S h = drop ? drop_step_limit(h_lim, k1) : S(h_lim);
        if (ripple > 0.0) h = ripple_step_limit(h, ripple, k1);
        h = std::min(remaining, h);
        substep(t, h, &k1);
        t += h;
        remaining -= h;
      }
      return;
    }
    const std::optional<long> steps =
        to_integer(std::ceil(value_of(len) / h_lim - 1e-9), 0L, std::numeric_limits<long>::max());
    if (!steps)
      fail("an interval of {} s between rows is more steps of {} s than the integrator counts", value_of(len),
           h_lim);
    const long n = std::max(1L, *steps);
    const S h = len / static_cast<double>(n);
    S t = m_t;
    for (long k = 0; k < n; ++k) {
      substep(t, h);
      t += h;
    }
  }

  /// The fastest-varying ripple's phase per rad of shaft angle (TorqueTerm::angle_rate), 0 for none.
  double ripple_rate() const {
    double rate = 0.0;
    for (const auto& term : m_c.motor_torque) rate = std::max(rate, term.angle_rate);
    return rate;
  }

  /// Step bound under a ripple of `rate`, at most h_max: its phase moves at most
  /// k_phase_per_step at the fastest speed the step may reach, |w| + |dw/dt| h_max, up to
  /// SimOptions::ripple_speed_rad_s. k = f(y) at the start. It follows the state, so on dual
  /// numbers it carries the state's derivatives: the sensitivities are those of the steps the
  /// simulation takes.
  S ripple_step_limit(const S& h_max, double rate, const Vec& k) const {
    const S cap_rad_s = m_opt.ripple_speed_rad_s > 0.0 ? S(m_opt.ripple_speed_rad_s)
                                                       : m_c.p.supply_V / m_c.p.motor.Ke_V_s_rad;
    const S reach_rad_s = std::min(cap_rad_s, abs(m_y[W_M]) + abs(k[W_M]) * h_max);
    return reach_rad_s > 0.0 ? std::min(h_max, k_phase_per_step / (rate * reach_rad_s)) : h_max;
  }

  /// Whether a circuit is integrated as a state (and so carries a saturating drop's slope).
  bool drop_circuits() const { return m_lam[I_M] != 0.0 || m_lam[I_G] != 0.0; }

  /// Step bound under a saturating drop, at most h_max. The exponential step takes the drop's
  /// slope s(i) = V_sat / i_sat sech^2(i / i_sat) at the step's start i0; the rest of it,
  /// (s(i) - s(i0)) / L, is stepped explicitly, so the step is held to half L over the
  /// largest change of the slope over the currents i0 +- |di/dt| h_max the step may reach: the
  /// full h_max where the current rests near zero or runs far from it, a few microseconds
  /// while it crosses zero. k = f(y) at the start. On dual numbers as ripple_step_limit.
  S drop_step_limit(double h_max, const Vec& k) const {
    const S V_sat = m_c.circuit.V_sat_V, i_sat = m_c.circuit.i_sat_A;
    auto slope = [&](const S& i) {
      const S th = tanh(i / i_sat);
      return V_sat / i_sat * (1.0 - th * th);
    };
    auto limit = [&](const S& i, const S& di, const S& R, const S& L) {
      const S reach = abs(di) * h_max;
      const S nearest = std::max(S(0.0), abs(i) - reach);
      const S s0 = slope(i);
      const S change = std::max(slope(nearest) - s0, s0 - slope(abs(i) + reach));
      return 0.5 * L / (R + change);
    };
    S h = h_max;
    if (m_lam[I_M] != 0.0) h = std::min(h, limit(m_y[I_M], k[I_M], m_R_bridge_ohm, m_c.p.motor.L_H));
    if (m_lam[I_G] != 0.0) {
      const BasicMachine<S>& mg = m_c.p.generator;
      h = std::min(h, limit(m_y[I_G], k[I_G], mg.R_ohm + m_r_load, mg.L_H));
    }
    return h;
  }

  enum class EventKind { none, motor_zero, gen_zero, motor_break, gen_break, slip_zero };

  /// Root in (0, 1] of the cubic Hermite interpolant of g with g(0) = g0 >= 0, g(1) = g1 <= 0.
  /// The root's derivatives follow from the implicit function theorem (root_at): the event's
  /// time moves with the parameters.
  static S hermite_root(const S& g0, const S& d0, const S& g1, const S& d1) {
    auto g = [&](const auto& s, const auto& a0, const auto& b0, const auto& a1, const auto& b1) {
      const auto s2 = s * s, s3 = s2 * s;
      return (2 * s3 - 3 * s2 + 1) * a0 + (s3 - 2 * s2 + s) * b0 + (-2 * s3 + 3 * s2) * a1 + (s3 - s2) * b1;
    };
    const double v0 = value_of(g0), e0 = value_of(d0), v1 = value_of(g1), e1 = value_of(d1);
    double lo = 0.0, hi = 1.0;
    for (int it = 0; it < 50; ++it) {
      const double mid = 0.5 * (lo + hi);
      if (g(mid, v0, e0, v1, e1) > 0.0) {
        lo = mid;
      } else {
        hi = mid;
      }
    }
    const double s2 = hi * hi;
    const double slope = (6 * s2 - 6 * hi) * v0 + (3 * s2 - 4 * hi + 1) * e0 + (-6 * s2 + 6 * hi) * v1 +
                         (3 * s2 - 2 * hi) * e1;
    return root_at(hi, g(S(hi), g0, d0, g1, d1), slope);
  }
  static S break_fraction(S T0, S T1, S Ts) {
    const S bound = T1 > 0.0 ? Ts : -Ts;
    if (abs(T0) > Ts || T1 == T0) return 0.0;
    return clamp((bound - T0) / (T1 - T0), 0.0, 1.0);
  }

  /// The torque the motor's shaft transmits at y, for the friction modifiers that need it.
  S motor_load(const Vec& y) const {
    return m_c.friction_needs_load ? abs(m_c.p.motor.Kt_Nm_A * motor_current(y)) : 0.0;
  }
  S motor_breakaway(const Vec& y) const {
    return m_c.breakaway(rigid() ? m_c.rigid : motor_friction(), motor_load(y));
  }
  S motor_breakaway() const { return motor_breakaway(m_y); }

  /// Breakaway rate of the stuck motor body (or rigid pair) at y under drive torque T, 1/s, on
  /// the regularised stick (k_stick_width): the hazard it gathers while stuck reaches 1 at the
  /// breakaway, which so moves continuously with Ts and with the drive, also at a step.
  S break_rate(S T, const Vec& y) const {
    const Friction& f = rigid() ? m_c.rigid : motor_friction();
    if (abs(T) <= f.Tc_Nm) return 0.0;
    const S Ts = motor_breakaway(y);
    if (Ts <= 0.0) return std::numeric_limits<double>::infinity();
    return exp((abs(T) - Ts) / (k_stick_width * Ts)) / k_stick_time_s;
  }
  S gen_breakaway() const { return m_c.breakaway(m_c.gen); }

  /// Steps h_total from the state, handling the events within it; k_start = f(y) at the start
  /// when the caller has it.
  void substep(S t0, S h_total, const Vec* k_start = nullptr) {
    S t = t0;
    S remaining = h_total;
    for (int events = 0; remaining > 0.0; ++events) {
      Vec k1;
      if (events == 0 && k_start != nullptr) {
        k1 = *k_start;
      } else {
        deriv(m_y, t, k1);
      }
      Vec y1 = step_once(m_y, t, remaining, k1);
      if (events >= k_max_events_per_step) {
        accept(y1, t + remaining);
        return;
      }
      const bool two_bodies = !rigid() && gen_present();
      S best = 2.0;
      EventKind kind = EventKind::none;
      Vec k_end{};
      bool have_k_end = false;
      auto end_derivative = [&]() -> const Vec& {
        if (!have_k_end) {
          deriv(y1, t + remaining, k_end);
          have_k_end = true;
        }
        return k_end;
      };
      S Tm0 = 0.0, Tg0 = 0.0, Tm1 = 0.0, Tg1 = 0.0;
      if (m_stuck_m || (two_bodies && m_stuck_g)) {
        drive_torques(m_y, t, Tm0, Tg0);
        drive_torques(y1, t + remaining, Tm1, Tg1);
      }
      // Motor body (or the rigid pair); on the regularised stick its breakaway hazard over the step.
      S hazard = 0.0;
      if (!m_stuck_m) {
        if (m_dir_m * y1[W_M] <= 0.0) {
          const S s = hermite_root(m_dir_m * m_y[W_M], m_dir_m * k1[W_M] * remaining, m_dir_m * y1[W_M],
                                   m_dir_m * end_derivative()[W_M] * remaining);
          if (s < best) {
            best = s;
            kind = EventKind::motor_zero;
          }
        }
      } else if (m_opt.smooth_stick) {
        hazard = 0.5 * (break_rate(Tm0, m_y) + break_rate(Tm1, y1)) * remaining;
        if (m_hazard_m + hazard >= 1.0) {
          best = clamp((1.0 - m_hazard_m) / hazard, 0.0, 1.0);
          kind = EventKind::motor_break;
        }
      } else if (abs(Tm1) > motor_breakaway(y1)) {
        const S s = break_fraction(Tm0, Tm1, motor_breakaway(y1));
        if (s < best) {
          best = s;
          kind = EventKind::motor_break;
        }
      }
      if (two_bodies) {
        if (!m_stuck_g) {
          if (m_dir_g * y1[W_G] <= 0.0) {
            const S s = hermite_root(m_dir_g * m_y[W_G], m_dir_g * k1[W_G] * remaining, m_dir_g * y1[W_G],
                                     m_dir_g * end_derivative()[W_G] * remaining);
            if (s < best) {
              best = s;
              kind = EventKind::gen_zero;
            }
          }
        } else if (abs(Tg1) > gen_breakaway()) {
          const S s = break_fraction(Tg0, Tg1, gen_breakaway());
          if (s < best) {
            best = s;
            kind = EventKind::gen_break;
          }
        }
        if (m_coupling == Coupling::slip) {
          const S r1 = m_slip_dir * (y1[W_M] - y1[W_G]);
          if (r1 <= 0.0) {
            const Vec& ke = end_derivative();
            const S s =
                hermite_root(m_slip_dir * (m_y[W_M] - m_y[W_G]), m_slip_dir * (k1[W_M] - k1[W_G]) * remaining,
                             r1, m_slip_dir * (ke[W_M] - ke[W_G]) * remaining);
            if (s < best) {
              best = s;
              kind = EventKind::slip_zero;
            }
          }
        }
      }
      if (kind == EventKind::none) {
        m_hazard_m += hazard;
        accept(y1, t + remaining);
        check_unlock(t);
        return;
      }
      const S h_event = best * remaining;
      m_hazard_m += best * hazard;
      if (best < 1.0) y1 = h_event > 0.0 ? step_once(m_y, t, h_event, k1) : m_y;
      accept(y1, t + h_event);
      t += h_event;
      remaining -= h_event;
      if (remaining < 1e-15) remaining = 0.0;
      apply_event(kind, t);
    }
  }

  void accept(const Vec& y, S t) {
    m_y = y;
    if (!m_stuck_m) m_hazard_m = 0.0;
    if (rigid()) m_y[W_G] = m_y[W_M];
    if (m_stuck_m) m_y[W_M] = 0.0;
    if (rigid() && m_stuck_m) m_y[W_G] = 0.0;
    if (!rigid() && (m_stuck_g || !gen_present())) m_y[W_G] = 0.0;
    if (!gen_circuit()) m_y[I_G] = 0.0;
    if (m_motor_quasi) m_y[I_M] = motor_current(m_y);
    (void)t;
  }

  void apply_event(EventKind kind, S t) {
    S Tm = 0.0, Tg = 0.0;
    switch (kind) {
      case EventKind::none:
        break;
      case EventKind::motor_zero:
        m_y[W_M] = 0.0;
        if (rigid()) m_y[W_G] = 0.0;
        drive_torques(m_y, t, Tm, Tg);
        // On the regularised stick the body stops, and its breakaway hazard decides when it goes.
        m_hazard_m = 0.0;
        if (m_opt.smooth_stick || abs(Tm) <= motor_breakaway()) {
          m_stuck_m = true;
        } else {
          m_dir_m = sign_of(Tm);
        }
        break;
      case EventKind::gen_zero:
        m_y[W_G] = 0.0;
        drive_torques(m_y, t, Tm, Tg);
        if (abs(Tg) <= gen_breakaway()) {
          m_stuck_g = true;
        } else {
          m_dir_g = sign_of(Tg);
        }
        break;
      case EventKind::motor_break:
        drive_torques(m_y, t, Tm, Tg);
        m_hazard_m = 0.0;
        if (m_opt.smooth_stick ? Tm != 0.0 : abs(Tm) > motor_breakaway()) {
          m_stuck_m = false;
          m_dir_m = sign_of(Tm);
        }
        break;
      case EventKind::gen_break:
        drive_torques(m_y, t, Tm, Tg);
        if (abs(Tg) > gen_breakaway()) {
          m_stuck_g = false;
          m_dir_g = sign_of(Tg);
        }
        break;
      case EventKind::slip_zero:
        try_lock(t);
        break;
    }
  }

  /// Torque the plates must carry to keep the shafts together (a coupling's capacity), from the
  /// common acceleration of the locked pair: T = Tm - Fm - Jm a.
  S locked_torque(S t, S& Tm_out) const {
    S Tm = 0.0, Tg = 0.0;
    drive_torques(m_y, t, Coupling::none, Tm, Tg);
    Tm_out = Tm;
    const S w = m_y[W_M];
    const int dir = sign_of(w);
    const S Fm = dir * m_c.kinetic(m_c.motor_side[2], dir * w, motor_load(m_y));
    const S Fg = dir * m_c.kinetic(m_c.gen, dir * w);
    const S a = (Tm - Fm + Tg - Fg) / m_c.J_total;
    return Tm - Fm - m_c.p.motor.J_kg_m2 * a;
  }

  void try_lock(S t) {
    const S J = m_c.J_total;
    const S w = (m_c.p.motor.J_kg_m2 * m_y[W_M] + m_c.p.generator.J_kg_m2 * m_y[W_G]) / J;
    m_y[W_M] = w;
    m_y[W_G] = w;
    S Tm = 0.0;
    const S T_req = locked_torque(t, Tm);
    if (w == 0.0 || abs(T_req) <= capacity(t)) {
      lock(w);
    } else {
      m_slip_dir = sign_of(T_req);
    }
  }

  void lock(S w) {
    if (spring()) {
      m_coupling = Coupling::spring;
      m_phi0 = m_y[TH_M] - m_y[TH_G];
      m_stuck_m = m_stuck_g = (w == 0.0);
      m_dir_m = m_dir_g = sign_of(w);
    } else {
      m_coupling = Coupling::rigid;
      m_y[W_M] = m_y[W_G] = w;
      m_stuck_m = (w == 0.0);
      m_dir_m = sign_of(w);
    }
  }

  /// A locked pair (rigid, with a capacity) slips again when the plates cannot carry the
  /// torque: moving, |T_req| > T_cap; at rest, the motor side alone exceeds its static level
  /// plus the capacity.
  void check_unlock(S t) {
    if (m_c.coupling.capacity == nullptr || m_coupling != Coupling::rigid || m_clutch != 2) return;
    const S cap = capacity(t);
    S Tm = 0.0;
    const S T_req = locked_torque(t, Tm);
    if (m_stuck_m) {
      if (abs(Tm) > m_c.breakaway(m_c.motor_side[2], motor_load(m_y)) + cap) {
        m_coupling = Coupling::slip;
        m_slip_dir = sign_of(Tm);
        m_stuck_g = true;
        m_stuck_m = false;
        m_dir_m = sign_of(Tm);
      }
      return;
    }
    if (abs(T_req) > cap) {
      m_coupling = Coupling::slip;
      m_slip_dir = sign_of(T_req);
      m_stuck_g = false;
      m_dir_g = m_dir_m;
    }
  }

  void set_load(double r_load) {
    if (r_load == m_r_load) return;
    m_r_load = r_load;
    update_gen_mode();
    if (!gen_circuit()) m_y[I_G] = 0.0;
    if (gen_quasi_static()) m_y[I_G] = gen_current(m_y);
  }

  void set_clutch(int next) {
    if (next == m_clutch) return;
    if (m_clutch == 2 && m_coupling == Coupling::rigid) {
      m_y[W_G] = m_y[W_M];
      m_stuck_g = m_stuck_m;
      m_dir_g = m_dir_m;
    }
    m_coupling = Coupling::none;
    if (next == 0 || m_clutch == 0) {
      // The generator is absent in state 0 and joins at rest.
      m_y[W_G] = 0.0;
      m_y[I_G] = 0.0;
      m_stuck_g = true;
      m_dir_g = 0;
    }
    m_clutch = next;
    update_gen_mode();
    if (next == 2) {
      const S Jm = m_c.p.motor.J_kg_m2, Jg = m_c.p.generator.J_kg_m2;
      if (m_c.coupling.capacity != nullptr) {
        m_t_engage = m_t;
        if (m_y[W_M] == m_y[W_G]) {
          lock(m_y[W_M]);
        } else {
          m_coupling = Coupling::slip;
          m_slip_dir = sign_of(m_y[W_M] - m_y[W_G]);
        }
      } else if (spring()) {
        m_coupling = Coupling::spring;
        m_phi0 = m_y[TH_M] - m_y[TH_G];
      } else {
        // Rigid engagement conserves angular momentum.
        const S w = (Jm * m_y[W_M] + Jg * m_y[W_G]) / (Jm + Jg);
        m_coupling = Coupling::rigid;
        m_y[W_M] = m_y[W_G] = w;
        m_stuck_m = (w == 0.0);
        m_dir_m = sign_of(w);
      }
    }
    if (gen_quasi_static()) m_y[I_G] = gen_current(m_y);
  }

  C m_c;
  SimOptions m_opt;
  S m_t = 0.0;
  double m_row_s = 0.0;  ///< the interval between the rows being stepped (step's dt)
  Vec m_y{};
  int m_clutch = 2;
  Coupling m_coupling = Coupling::none;
  bool m_stuck_m = true;
  bool m_stuck_g = true;
  S m_hazard_m = 0.0;  ///< breakaway hazard the stuck motor body gathered (smooth_stick)
  int m_dir_m = 0;
  int m_dir_g = 0;
  int m_slip_dir = 0;
  S m_phi0 = 0.0;
  S m_t_engage = 0.0;
  double m_r_load = k_open_circuit;
  bool m_gen_circuit = false;
  bool m_gen_quasi = false;
  bool m_motor_quasi = false;                ///< the motor current solved as algebraic (see motor_current)
  mutable std::array<CoefMemo, 2> m_coef{};  ///< per circuit, the coefficients of recent steps
  double m_v = 0.0;
  S m_duty = 0.0;               ///< the bridge's duty d' at m_v (set_bridge)
  S m_v_bridge = 0.0;           ///< its output d' supply_V, V
  S m_emf_share = 1.0;          ///< the back-emf's share of the period at m_duty (emf_share)
  S m_R_bridge_ohm = 0.0;       ///< R + R_series + |d'| R_duty, ohm
  Vec m_lam{};                  ///< the circuits' decay rates (update_rates), 1/s
  S m_i_cmd = std::numeric_limits<double>::quiet_NaN();  ///< Drive::i_cmd_A in force
  /// Commands waiting out the drive's dead time: when each acts, and what it commands.
  struct Queued {
    S t_s;
    double v_V;
    S i_cmd_A;
  };
  std::deque<Queued> m_queue;
};

class PlantImpl : public PlantCore<double, Compiled> {
 public:
  using PlantCore::PlantCore;
};

namespace {

/// Steps `compiled` through the rows of `in` from rest at t_s[0] (initial clutch = clutch[0]),
/// handing on_row(k, state) row k's state: at t_k, just before row k's inputs (and a clutch or
/// relay switch at t_k) act. A torque drive commands the current T / kt_cmd_Nm_A.
template <class S, class C, class OnRow>
void run_rows(C compiled, const S& kt_cmd_Nm_A, const Inputs& in, const SimOptions& options, OnRow&& on_row) {
  const std::size_t n = in.t_s.size();
  MCG_DEMAND(in.v_V.size() == n && in.clutch.size() == n && in.r_load_ohm.size() == n);
  MCG_DEMAND((in.i_cmd_A.empty() || in.i_cmd_A.size() == n) &&
             (in.T_cmd_Nm.empty() || in.T_cmd_Nm.size() == n));
  MCG_DEMAND(in.i_cmd_A.empty() || in.T_cmd_Nm.empty());
  if (n == 0) return;
  PlantCore<S, C> plant(std::move(compiled), options, static_cast<int>(in.clutch[0]));
  for (std::size_t k = 0; k < n; ++k) {
    const Drive drive{in.v_V[k], static_cast<int>(in.clutch[k]), in.r_load_ohm[k]};
    S i_cmd_A = drive.i_cmd_A;
    if (!in.i_cmd_A.empty()) i_cmd_A = in.i_cmd_A[k];
    if (!in.T_cmd_Nm.empty()) i_cmd_A = in.T_cmd_Nm[k] / kt_cmd_Nm_A;
    on_row(k, plant.state());
    if (k + 1 < n) plant.step(in.t_s[k + 1] - in.t_s[k], drive, i_cmd_A);
  }
}

}  // namespace

Outputs simulate(const Model& model, const Inputs& in, const SimOptions& options) {
  Outputs out;
  out.resize(in.t_s.size());
  run_rows(Compiled(model), model.params.motor.Kt_Nm_A, in, options,
           [&](std::size_t k, const State& state) { out.store(k, state); });
  return out;
}

void simulate_states(const CompiledDual& compiled, const Dual& kt_cmd_Nm_A, const Inputs& in,
                     const SimOptions& options,
                     const std::function<void(std::size_t, const BasicState<Dual>&)>& on_row) {
  run_rows(compiled, kt_cmd_Nm_A, in, options, on_row);
}

Plant::Plant(const Model& model, const SimOptions& options, int initial_clutch)
    : m_impl(new PlantImpl(Compiled(model), options, initial_clutch)) {}
Plant::~Plant() { delete m_impl; }
Plant::Plant(const Plant& other) : m_impl(new PlantImpl(*other.m_impl)) {}
Plant& Plant::operator=(const Plant& other) {
  if (this != &other) *m_impl = *other.m_impl;
  return *this;
}
Plant::Plant(Plant&& other) noexcept : m_impl(other.m_impl) { other.m_impl = nullptr; }
Plant& Plant::operator=(Plant&& other) noexcept {
  std::swap(m_impl, other.m_impl);
  return *this;
}
void Plant::step(double dt_s, const Drive& drive) { m_impl->step(dt_s, drive, drive.i_cmd_A); }
void Plant::start_at(double omega_rad_s) { m_impl->start_at(omega_rad_s); }
State Plant::state() const { return m_impl->state(); }
double Plant::time_s() const { return m_impl->time(); }

}  // namespace mcg::model
