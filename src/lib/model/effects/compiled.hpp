// The plant's hooks: the model with every effect resolved into plain numbers and functions for
// the integrator's inner loop (model/plant.cpp). An effect module (model/effects/<name>.cpp)
// fills these hooks in its compile function and keeps its equations there; the plant knows
// the kinds of physics below, never an effect. A new effect that fits these hooks touches no
// other file than its own and the catalog's registry.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "model/model.hpp"

namespace mcg::model {

inline Friction operator+(const Friction& a, const Friction& b) {
  Friction f;
  f.Ts_Nm = a.Ts_Nm + b.Ts_Nm;
  f.Tc_Nm = a.Tc_Nm + b.Tc_Nm;
  for (std::size_t k = 0; k < 3; ++k) f.viscous[k] = a.viscous[k] + b.viscous[k];
  return f;
}

/// A torque on the motor shaft, N m, a smooth function of the motor angle and speed with up
/// to four numbers of the effect: T = fn(k, theta_rad, omega_rad_s). It is part of the drive
/// torque, so it takes part in stick-slip (a stuck shaft breaks away when the sum of the
/// drive torques leaves the static band).
struct TorqueTerm {
  double (*fn)(const std::array<double, 4>& k, double theta_rad, double omega_rad_s) = nullptr;
  std::array<double, 4> k{};
  /// Used instead of fn when set: a term of the motor current and time too (ShaftTerm::basis_it).
  double (*fn_it)(const std::array<double, 4>& k, double theta_rad, double omega_rad_s, double i_A,
                  double t_s) = nullptr;
  /// How fast it varies with the shaft angle, rad of its phase per rad of shaft: N for a ripple
  /// sin(N theta + phase), 0 for a term without the angle, negative when unknown. The step
  /// resolves it (plant.cpp: ripple_step_limit; unknown, step_limit's electrical bound).
  double angle_rate = -1.0;

  double operator()(double theta_rad, double omega_rad_s, double i_A, double t_s) const {
    return fn_it ? fn_it(k, theta_rad, omega_rad_s, i_A, t_s) : fn(k, theta_rad, omega_rad_s);
  }
};

/// A friction modifier: added to every friction element's kinetic level at speed x = dir w
/// (fn), and to its breakaway level (breakaway; nullptr adds nothing), given the element's
/// own levels and load_Nm, the torque the motor's shaft transmits (|Kt i| of the motor for
/// the motor's element and the rigid pair, 0 for the generator's own).
struct FrictionTerm {
  double (*fn)(const std::array<double, 4>& k, const Friction& f, double x, double load_Nm) = nullptr;
  double (*breakaway)(const std::array<double, 4>& k, double load_Nm) = nullptr;
  std::array<double, 4> k{};
};

/// Circuit voltage-drop terms. Motor: L di/dt = d' supply_V - (R + R_series + |d'| R_duty) i
/// - emf_share(d') Ke w - drop(i), d' = sign(d) max(0, |d| - deadband), d = v / supply_V clamped
/// to 1; generator: L di/dt = Ke w - (R + r_load) i - drop(i). drop(i) = V_sat tanh(i / i_sat).
struct CircuitTerms {
  double R_series_ohm = 0.0;  ///< in series with the motor at any duty
  double R_duty_ohm = 0.0;    ///< in series with the motor in proportion to the duty
  double deadband = 0.0;      ///< duty lost per period
  double V_sat_V = 0.0;       ///< saturating drop in both circuits (0: none)
  double i_sat_A = 1.0;       ///< its current scale
  double coast = 0.0;         ///< share of the PWM off-time the motor current is zero

  double duty(double d) const {
    return deadband > 0.0 ? std::copysign(std::max(0.0, std::abs(d) - deadband), d) : d;
  }
  /// Share of the period the back-EMF opposes the current at duty d': 1 - coast (1 - |d'|)
  /// (in the coasting share the open terminals carry Ke w and no current).
  double emf_share(double d) const { return coast > 0.0 ? 1.0 - coast * (1.0 - std::abs(d)) : 1.0; }
  double drop(double i_A) const { return V_sat_V * std::tanh(i_A / i_sat_A); }
};

/// Extra states, one per winding (motor, generator): x' = rate(k, P_W, x), P = i^2 R the
/// winding's loss; the winding's resistance is R0 (1 + R_per_x x); x(0) = x0.
struct WindingStates {
  double (*rate)(const std::array<double, 4>& k, double P_W, double x) = nullptr;
  std::array<double, 4> k{};
  double R_per_x = 0.0;
  double x0 = 0.0;
};

/// The engaged clutch: rigid, or a spring and damper (spring_k_Nm_rad > 0, damping ratio
/// zeta of the two-rotor mode); with a capacity, the plates carry at most capacity(k, age_s)
/// at age_s after an engage command and slip until they lock.
struct CouplingTerms {
  double spring_k_Nm_rad = 0.0;
  double zeta = 0.0;
  double (*capacity)(const std::array<double, 4>& k, double age_s) = nullptr;
  std::array<double, 4> capacity_k{};
};

struct Compiled {
  /// The nominal parameters; an effect may change them (param_mismatch scales them).
  Params p;
  /// Transport delay of the applied voltage, s (the nominal drive.dead_time_s plus effects).
  double delay_s = 0.0;
  CircuitTerms circuit;
  WindingStates winding;
  CouplingTerms coupling;
  std::vector<FrictionTerm> friction_terms;
  /// Further torques on the motor shaft (cogging, a direction bias, ...).
  std::vector<TorqueTerm> motor_torque;

  // Derived after every effect has compiled (finish()).
  Friction motor_side[3];  ///< friction on the motor body when the bodies are separate, per state
  Friction rigid;          ///< motor + engaged clutch + generator
  Friction gen;            ///< the generator's own
  double J_total = 0.0;
  double c_spring = 0.0;             ///< 2 zeta sqrt(k Jm Jg / (Jm + Jg)), N m s/rad
  bool friction_needs_load = false;  ///< a friction term's breakaway depends on the transmitted torque

  /// Compiles the model's effects in catalog order, then derives the sums.
  explicit Compiled(const Model& model);

  /// Kinetic friction magnitude at speed x = dir * w (x may dip slightly below 0 inside an
  /// RK4 stage; the polynomial continues smoothly there), load_Nm as for FrictionTerm.
  double kinetic(const Friction& f, double x, double load_Nm = 0.0) const {
    double F = f.kinetic_Nm(x);
    for (const FrictionTerm& term : friction_terms) F += term.fn(term.k, f, x, load_Nm);
    return F;
  }
  /// Breakaway level: the static level, or the kinetic level at 0+ if that is larger
  /// (otherwise a released body would be pulled back at once), plus the modifiers'.
  double breakaway(const Friction& f, double load_Nm = 0.0) const {
    double B = f.Ts_Nm > f.Tc_Nm ? f.Ts_Nm : f.Tc_Nm;
    for (const FrictionTerm& term : friction_terms) {
      if (term.breakaway != nullptr) B += term.breakaway(term.k, load_Nm);
    }
    return B;
  }
  /// Sum of the effects' torques on the motor shaft.
  double extra_motor_torque(double theta_rad, double omega_rad_s, double i_A, double t_s) const {
    double T = 0.0;
    for (const TorqueTerm& term : motor_torque) T += term(theta_rad, omega_rad_s, i_A, t_s);
    return T;
  }
};

/// The param_mismatch scale that moves nominal parameter `name` ("motor.R_ohm": "R_scale"),
/// empty when none does; read off param_mismatch's own compile step (param_mismatch.cpp).
std::string mismatch_scale_of(std::string_view name);

}  // namespace mcg::model
