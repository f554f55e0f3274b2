// The plant's hooks: the model with every effect resolved into plain numbers and functions for
// the integrator's inner loop (model/plant.cpp). An effect module (model/effects/<name>.cpp)
// fills these hooks in its compile function and keeps its equations there; the plant knows
// the kinds of physics below, never an effect. A new effect that fits these hooks touches no
// other file than its own and the catalog's registry.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <vector>

#include "model/dual.hpp"
#include "model/model.hpp"

namespace mcg::model {

template <class S>
BasicFriction<S> operator+(const BasicFriction<S>& a, const BasicFriction<S>& b) {
  BasicFriction<S> f;
  f.Ts_Nm = a.Ts_Nm + b.Ts_Nm;
  f.Tc_Nm = a.Tc_Nm + b.Tc_Nm;
  for (std::size_t k = 0; k < 3; ++k) f.viscous[k] = a.viscous[k] + b.viscous[k];
  return f;
}

// Every hook below exists twice: on double for the simulation, on Dual for its sensitivities
// (model/sensitivity.hpp). An effect writes its functions once, as templates, and hands the
// hook both instantiations; a hook whose Dual function is nullptr (a discrepancy term's) has
// no sensitivities, and the fits take finite differences for a model with it.

/// A torque on the motor shaft, N m, a smooth function of the motor angle and speed with up
/// to four numbers of the effect: T = fn(k, theta_rad, omega_rad_s). It is part of the drive
/// torque, so it takes part in stick-slip (a stuck shaft breaks away when the sum of the
/// drive torques leaves the static band).
template <class S>
using TorqueFn = S (*)(const std::array<S, 4>& k, S theta_rad, S omega_rad_s);
template <class S>
using TorqueFnIt = S (*)(const std::array<S, 4>& k, S theta_rad, S omega_rad_s, S i_A, S t_s);
template <class S>
struct BasicTorqueTerm {
  TorqueFn<S> fn = nullptr;
  std::array<S, 4> k{};
  /// Used instead of fn when set: a term of the motor current and time too (ShaftTerm::basis_it).
  TorqueFnIt<S> fn_it = nullptr;
  /// How fast it varies with the shaft angle, rad of its phase per rad of shaft: N for a ripple
  /// sin(N theta + phase), 0 for a term without the angle, negative when unknown. The step
  /// resolves it (plant.cpp: ripple_step_limit; unknown, step_limit's electrical bound).
  double angle_rate = -1.0;
  TorqueFn<Dual> fn_dual = nullptr;
  TorqueFnIt<Dual> fn_it_dual = nullptr;

  S operator()(const S& theta_rad, const S& omega_rad_s, const S& i_A, const S& t_s) const {
    return fn_it ? fn_it(k, theta_rad, omega_rad_s, i_A, t_s) : fn(k, theta_rad, omega_rad_s);
  }
};
using TorqueTerm = BasicTorqueTerm<double>;

/// A friction modifier: added to every friction element's kinetic level at speed x = dir w
/// (fn), and to its breakaway level (breakaway; nullptr adds nothing), given the element's
/// own levels and load_Nm, the torque the motor's shaft transmits (|Kt i| of the motor for
/// the motor's element and the rigid pair, 0 for the generator's own).
template <class S>
using FrictionFn = S (*)(const std::array<S, 4>& k, const BasicFriction<S>& f, S x, S load_Nm);
template <class S>
using BreakawayFn = S (*)(const std::array<S, 4>& k, S load_Nm);
template <class S>
struct BasicFrictionTerm {
  FrictionFn<S> fn = nullptr;
  BreakawayFn<S> breakaway = nullptr;
  std::array<S, 4> k{};
  FrictionFn<Dual> fn_dual = nullptr;
  BreakawayFn<Dual> breakaway_dual = nullptr;
};
using FrictionTerm = BasicFrictionTerm<double>;

/// Circuit voltage-drop terms. Motor: L di/dt = d' supply_V - (R + R_series + |d'| R_duty) i
/// - emf_share(d') Ke w - drop(i), d' = sign(d) max(0, |d| - deadband), d = v / supply_V clamped
/// to 1; generator: L di/dt = Ke w - (R + r_load) i - drop(i). drop(i) = V_sat tanh(i / i_sat).
template <class S>
struct BasicCircuitTerms {
  S R_series_ohm = 0.0;  ///< in series with the motor at any duty
  S R_duty_ohm = 0.0;    ///< in series with the motor in proportion to the duty
  S deadband = 0.0;      ///< duty lost per period
  S V_sat_V = 0.0;       ///< saturating drop in both circuits (0: none)
  S i_sat_A = 1.0;       ///< its current scale
  S coast = 0.0;         ///< share of the PWM off-time the motor current is zero

  S duty(const S& d) const {
    using std::abs;
    using std::copysign;
    return deadband > 0.0 ? copysign(std::max(S(0.0), abs(d) - deadband), d) : d;
  }
  /// Share of the period the back-EMF opposes the current at duty d': 1 - coast (1 - |d'|)
  /// (in the coasting share the open terminals carry Ke w and no current).
  S emf_share(const S& d) const {
    using std::abs;
    return coast > 0.0 ? 1.0 - coast * (1.0 - abs(d)) : S(1.0);
  }
  S drop(const S& i_A) const {
    using std::tanh;
    return V_sat_V * tanh(i_A / i_sat_A);
  }
};
using CircuitTerms = BasicCircuitTerms<double>;

/// Extra states, one per winding (motor, generator): x' = rate(k, P_W, x), P = i^2 R the
/// winding's loss; the winding's resistance is R0 (1 + R_per_x x); x(0) = x0.
template <class S>
using WindingFn = S (*)(const std::array<S, 4>& k, S P_W, S x);
template <class S>
struct BasicWindingStates {
  WindingFn<S> rate = nullptr;
  std::array<S, 4> k{};
  S R_per_x = 0.0;
  S x0 = 0.0;
  WindingFn<Dual> rate_dual = nullptr;
};

/// The engaged clutch: rigid, or a spring and damper (spring_k_Nm_rad > 0, damping ratio
/// zeta of the two-rotor mode); with a capacity, the plates carry at most capacity(k, age_s)
/// at age_s after an engage command and slip until they lock.
template <class S>
using CapacityFn = S (*)(const std::array<S, 4>& k, S age_s);
template <class S>
struct BasicCouplingTerms {
  S spring_k_Nm_rad = 0.0;
  S zeta = 0.0;
  CapacityFn<S> capacity = nullptr;
  std::array<S, 4> capacity_k{};
  CapacityFn<Dual> capacity_dual = nullptr;
};

/// The model with its effects resolved, on numbers of type S (Compiled below, or CompiledDual:
/// the same with the derivatives of every number, model/sensitivity.hpp).
template <class S>
struct BasicCompiled {
  /// The nominal parameters; an effect may change them (param_mismatch scales them).
  BasicParams<S> p;
  /// Transport delay of the applied voltage, s (the nominal drive.dead_time_s plus effects).
  S delay_s = 0.0;
  BasicCircuitTerms<S> circuit;
  BasicWindingStates<S> winding;
  BasicCouplingTerms<S> coupling;
  std::vector<BasicFrictionTerm<S>> friction_terms;
  /// Further torques on the motor shaft (cogging, a direction bias, ...).
  std::vector<BasicTorqueTerm<S>> motor_torque;

  // Derived after every effect has compiled.
  BasicFriction<S> motor_side[3];  ///< friction on the motor body when the bodies are separate, per state
  BasicFriction<S> rigid;          ///< motor + engaged clutch + generator
  BasicFriction<S> gen;            ///< the generator's own
  S J_total = 0.0;
  S c_spring = 0.0;                  ///< 2 zeta sqrt(k Jm Jg / (Jm + Jg)), N m s/rad
  bool friction_needs_load = false;  ///< a friction term's breakaway depends on the transmitted torque

  /// Kinetic friction magnitude at speed x = dir * w (x may dip slightly below 0 inside an
  /// RK4 stage; the polynomial continues smoothly there), load_Nm as for FrictionTerm.
  S kinetic(const BasicFriction<S>& f, const S& x, const S& load_Nm = 0.0) const {
    S F = f.kinetic_Nm(x);
    for (const auto& term : friction_terms) F += term.fn(term.k, f, x, load_Nm);
    return F;
  }
  /// Breakaway level: the static level, or the kinetic level at 0+ if that is larger
  /// (otherwise a released body would be pulled back at once), plus the modifiers'.
  S breakaway(const BasicFriction<S>& f, const S& load_Nm = 0.0) const {
    S B = f.Ts_Nm > f.Tc_Nm ? f.Ts_Nm : f.Tc_Nm;
    for (const auto& term : friction_terms) {
      if (term.breakaway != nullptr) B += term.breakaway(term.k, load_Nm);
    }
    return B;
  }
  /// Sum of the effects' torques on the motor shaft.
  S extra_motor_torque(const S& theta_rad, const S& omega_rad_s, const S& i_A, const S& t_s) const {
    S T = 0.0;
    for (const auto& term : motor_torque) T += term(theta_rad, omega_rad_s, i_A, t_s);
    return T;
  }
};

struct Compiled : BasicCompiled<double> {
  /// Compiles the model's effects in catalog order, then derives the sums.
  explicit Compiled(const Model& model);
};

/// Compiled with the derivatives of every number (model/sensitivity.cpp lifts it).
using CompiledDual = BasicCompiled<Dual>;

/// simulate()'s rows on dual numbers: on_row(k, state) for each row in turn; kt_cmd_Nm_A
/// converts a torque drive's command to current (the simulated model's nominal Kt, with its
/// derivatives).
void simulate_states(const CompiledDual& compiled, const Dual& kt_cmd_Nm_A, const Inputs& inputs,
                     const SimOptions& options,
                     const std::function<void(std::size_t, const BasicState<Dual>&)>& on_row);

/// The param_mismatch scale that moves nominal parameter `name` ("motor.R_ohm": "R_scale"),
/// empty when none does; read off param_mismatch's own compile step (param_mismatch.cpp).
std::string mismatch_scale_of(std::string_view name);

}  // namespace mcg::model
