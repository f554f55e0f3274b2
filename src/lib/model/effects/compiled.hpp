// The plant's hooks: the model with every effect resolved into plain numbers for the
// integrator's inner loop (model/plant.cpp). An effect module (model/effects/<name>.cpp)
// writes its parameters into these fields in its compile function; the plant reads them.
// A new effect that fits these hooks touches no other file; one that needs a new kind of
// physics adds its hook here and its use in plant.cpp.
#pragma once

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

  double operator()(double theta_rad, double omega_rad_s, double i_A, double t_s) const {
    return fn_it ? fn_it(k, theta_rad, omega_rad_s, i_A, t_s) : fn(k, theta_rad, omega_rad_s);
  }
};

struct Compiled {
  /// The nominal parameters; an effect may change them (param_mismatch scales them).
  Params p;
  /// Transport delay of the applied voltage, s (the nominal drive.dead_time_s plus effects).
  double delay_s = 0.0;
  /// Friction curve: F(x) = Tc + (Ts - Tc) exp(-(x/v_s)^shape) + P(x) when `stribeck`.
  bool stribeck = false;
  double v_s = 1.0, shape = 1.0;
  /// Bridge: source resistance (drop |d| R_s i), two switches' on-resistance, duty deadband.
  double R_s = 0.0;
  double R_on2 = 0.0, deadband = 0.0;
  /// Brush contact drop V_b tanh(i / 0.01 A) in both armature circuits, V.
  double V_b = 0.0;
  /// Engaged clutch as a spring k and damper of damping ratio zeta_spring (c_spring derived).
  bool compliance = false;
  double k_spring = 0.0, zeta_spring = 0.0;
  /// Clutch torque capacity T_max (1 - exp(-(t - t_e)/tau_lag)) after an engage command.
  bool lag = false;
  double T_max = 0.0, tau_lag = 1.0;
  /// Winding heating: R = R0 (1 + alpha dT), C_th d(dT)/dt = i^2 R - dT/R_th.
  bool thermal = false;
  double R_th = 1.0, tau_th = 1.0, alpha = 0.0, dT0 = 0.0;
  /// Further torques on the motor shaft (cogging, a direction bias, ...).
  std::vector<TorqueTerm> motor_torque;

  // Derived after every effect has compiled (finish()).
  Friction motor_side[3];  ///< friction on the motor body when the bodies are separate, per state
  Friction rigid;          ///< motor + engaged clutch + generator
  Friction gen;            ///< the generator's own
  double J_total = 0.0;
  double c_spring = 0.0;  ///< 2 zeta sqrt(k Jm Jg / (Jm + Jg)), N m s/rad
  double C_th = 1.0;      ///< tau_th / R_th, J/K

  /// Compiles the model's effects in catalog order, then derives the sums.
  explicit Compiled(const Model& model);

  /// Kinetic friction magnitude at speed x = dir * w (x may dip slightly below 0 inside an
  /// RK4 stage; the polynomial continues smoothly there).
  double kinetic(const Friction& f, double x) const {
    double F = f.kinetic_Nm(x);
    if (stribeck && x > 0.0) {
      F += (f.Ts_Nm - f.Tc_Nm) * std::exp(-std::pow(x / v_s, shape));
    } else if (stribeck) {
      F += f.Ts_Nm - f.Tc_Nm;
    }
    return F;
  }
  /// Breakaway level: the static level, or the kinetic level at 0+ if that is larger
  /// (otherwise a released body would be pulled back at once).
  double breakaway(const Friction& f) const { return f.Ts_Nm > f.Tc_Nm ? f.Ts_Nm : f.Tc_Nm; }
  /// Sum of the effects' torques on the motor shaft.
  double extra_motor_torque(double theta_rad, double omega_rad_s, double i_A, double t_s) const {
    double T = 0.0;
    for (const TorqueTerm& term : motor_torque) T += term(theta_rad, omega_rad_s, i_A, t_s);
    return T;
  }
};

}  // namespace mcg::model
