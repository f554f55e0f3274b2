// The rig: motor, clutch and generator of the report, its parameters, effects and simulation.
//
// Physics (SI units throughout; w = shaft speed in rad/s, i = armature current in A):
//   motor armature       L di/dt = v_m - R i - Ke w_m                      (v_m: bridge output)
//   generator armature   L_g di_g/dt = Ke_g w_g - (R_g + r_load) i_g        (r_load = inf: i_g = 0)
//   rotors               J dw/dt = T_drive - sum_k F_k(w)
//   friction element k   F_k(w) = sign(w) (Tc_k + P_k(|w|)) while moving, P_k(x) = c1 x + c2 x^2 + c3 x^3;
//                        at rest the body stays at rest while |T_drive| <= sum_k Ts_k (true stick-slip)
//   clutch states        0: motor alone {motor}; 1: attached, disengaged {motor, clutch_disengaged},
//                        the generator a separate body {generator} that coasts; 2: engaged, one rigid
//                        body Jm + Jg {motor, clutch_engaged, generator}, momentum conserved on engaging
//   bridge               v_m = clamp(v, -supply_V, supply_V), delayed by dead_time_s
#pragma once

#include <array>
#include <limits>
#include <optional>
#include <iosfwd>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "boardunits/chain.hpp"  // k_supply_V

namespace mcg::config {
class Ini;
}

namespace mcg::model {

/// The brush drop's smoothing current: V_b tanh(i / k_brush_smooth_i_A) reaches 76 % of V_b at
/// 10 mA (the reference definition; brush_drop, and the diagnosis' term of its shape).
inline constexpr double k_brush_smooth_i_A = 0.01;

/// One friction element. Moving: F(w) = sign(w) (Tc_Nm + c1 |w| + c2 |w|^2 + c3 |w|^3);
/// at rest it holds up to Ts_Nm. The viscous polynomial is applied with odd symmetry.
/// S is the number type: double, or model::Dual where the plant carries sensitivities.
template <class S>
struct BasicFriction {
  S Ts_Nm = 0.0;                            ///< static (breakaway) level, N m
  S Tc_Nm = 0.0;                            ///< Coulomb level, N m
  std::array<S, 3> viscous{0.0, 0.0, 0.0};  ///< c1 [N m s/rad], c2 [N m s^2/rad^2], c3 [N m s^3/rad^3]

  /// Kinetic friction magnitude at speed |w| = x_rad_s (without Stribeck): Tc + P(x).
  S kinetic_Nm(const S& x_rad_s) const {
    return Tc_Nm + x_rad_s * (viscous[0] + x_rad_s * (viscous[1] + x_rad_s * viscous[2]));
  }
};
using Friction = BasicFriction<double>;

/// One DC machine (the motor, or the identical machine used as generator).
template <class S>
struct BasicMachine {
  S R_ohm = 0.0;              ///< armature resistance
  S L_H = 0.0;                ///< armature inductance
  S Kt_Nm_A = 0.0;            ///< torque constant
  S Ke_V_s_rad = 0.0;         ///< back-EMF constant (= Kt in SI units)
  S J_kg_m2 = 0.0;            ///< rotor inertia
  BasicFriction<S> friction;  ///< the machine's own bearing and brush friction
};
using Machine = BasicMachine<double>;

/// Every parameter of the rig, SI units. The INI form is described in docs/formats.md.
template <class S>
struct BasicParams {
  BasicMachine<S> motor;
  BasicMachine<S> generator;
  BasicFriction<S> clutch_disengaged;   ///< clutch attached, not engaged (state 1), on the motor shaft
  BasicFriction<S> clutch_engaged;      ///< clutch engaged (state 2), on the coupled shaft
  S supply_V = boardunits::k_supply_V;  ///< H-bridge supply: v = duty * supply_V, saturated at +-supply_V
  S dead_time_s = 0.0;                  ///< transport delay of the applied voltage (clutch/relay not delayed)
};
using Params = BasicParams<double>;

/// The report's rig (see model.cpp for the sources of every number and the inertia choice).
Params builtin_rig();

/// Reads the parameters present in `ini` over `base`; unknown keys in the model's sections
/// ([motor], [generator], [clutch_disengaged], [clutch_engaged], [drive]) are an error
/// naming the file and line; other sections are ignored. Throws mcg::Error on bad values.
Params from_ini(const config::Ini& ini, Params base = builtin_rig());
/// Writes every parameter of `params` into `ini` (with units as comments).
void to_ini(const Params& params, config::Ini& ini);

/// One optional effect of the catalog with its parameter values (all of the effect's
/// parameters, defaults filled in, in catalog order).
struct Effect {
  std::string name;
  std::vector<std::pair<std::string, double>> params;

  /// Value of parameter `key` (the catalog's default when not listed); the key must belong
  /// to the effect: an unknown effect or key throws mcg::Error (in every build type).
  double get(std::string_view key) const;
  /// Sets `key` (one of the effect's catalog parameters; anything else throws mcg::Error).
  void set(std::string_view key, double value);
};

/// Documentation of one effect parameter.
struct EffectParamSpec {
  std::string name;
  double default_value;
  double lower;
  double upper;
  std::string unit;
  std::string doc;
  /// A periodic parameter's period (a phase: 2 pi), 0 for none. Its range is one period, and a
  /// fit wraps it into the range rather than bounding it: no phase is ever "at a bound".
  double period = 0.0;
};

struct Compiled;

/// The friction the training runs show beyond the model's own (the gap diagnosis reads it from
/// steady states and starts from rest, through the same estimate on the data and on the model's
/// simulation, so the estimate's biases cancel): where a friction effect's fit starts.
struct DataFriction {
  double coulomb_Nm = 0.0;        ///< Coulomb level
  double static_excess_Nm = 0.0;  ///< breakaway beyond the Coulomb level
  double viscous_Nm_s_rad = 0.0;  ///< viscous coefficient
  double asymmetry_Nm = 0.0;      ///< half the forward-minus-reverse level (both_directions only)
  bool both_directions = false;   ///< the runs move the shaft both ways
};

/// The shapes of the catalog-free discrepancy terms (fit/discrepancy.cpp's library) a catalog
/// effect's fit can start from: what a term does, whatever its text.
enum class TermShape {
  none,              ///< seeds no effect
  sign,              ///< c tanh(w / eps): a level against (c < 0) or with the motion, N m
  abs_current_sign,  ///< c |i| sign(w): a level that grows with the current, N m/A
  angle_harmonic,    ///< c sin(N theta + phase) on the shaft, N m
  current_drop,      ///< a voltage c against the current in the motor circuit, V
  drive_dead_band,   ///< a voltage c lost from the drive's output in its direction, V
};

/// What a term shape is physically, as a report names it: "a Coulomb level", ...
inline const char* term_shape_text(TermShape shape) {
  switch (shape) {
    case TermShape::none:
      return "a term";
    case TermShape::sign:
      return "a Coulomb level";
    case TermShape::abs_current_sign:
      return "friction growing with the load";
    case TermShape::angle_harmonic:
      return "a torque periodic in the angle";
    case TermShape::current_drop:
      return "a brush drop";
    case TermShape::drive_dead_band:
      return "a dead band of the drive";
  }
  return "a term";
}

/// A discrepancy term's values: its coefficient in the unit of its shape, and for a harmonic
/// its order (cycles per revolution) and phase.
struct TermValues {
  double coefficient = 0.0;
  double order = 0.0;
  double phase_rad = 0.0;
};

/// A term shape an effect's fit starts from, and how: the effect's parameters (key, value) from
/// the term's values and the nominal parameters, or none when the values are not the effect's
/// (a sign or an order it cannot have). Values outside a parameter's range are clamped to it.
struct TermSeed {
  TermShape shape = TermShape::none;
  std::vector<std::pair<std::string, double>> (*start)(const TermValues& term,
                                                       const Params& nominal) = nullptr;
};

/// What drives the motor in a run (the fits' DriveInput): the bridge voltage (or duty), an ideal
/// current loop's command, or the drive torque itself (commanded as a current).
enum class DriveKind { voltage, current, torque };

/// The size of a drive, which the diagnosis scales an effect's starting grid by: the torque it
/// can apply to the motor shaft and the speed that shaft reaches (N m and rad/s; N and m/s on a
/// linear axis).
struct DriveScale {
  double torque_Nm = 0.0;
  double speed_rad_s = 0.0;
};

/// A voltage drive's size: the stall torque Kt supply_V / R and the no-load speed supply_V / Ke.
DriveScale voltage_drive_scale(const Params& p);

/// Per-key factors for a grid stated for the built-in rig's voltage drive
/// (voltage_drive_scale(builtin_rig())), from the units `kind` names per key: 'T' a torque
/// (drive.torque_Nm over the rig's), 'w' a speed (drive.speed_rad_s over the rig's), 'V' a
/// voltage (supply_V over the rig's), 'R' a resistance (the motor's R over the rig's), '1' (or
/// anything else) none.
/// The built-in rig's own voltage drive gets factors of exactly 1.
std::vector<double> builtin_grid_scale(std::string_view kind, const Params& nominal, const DriveScale& drive);

/// How a report names a drive: "a voltage-driven drive", ...
inline const char* drive_kind_text(DriveKind drive) {
  switch (drive) {
    case DriveKind::voltage:
      return "a voltage-driven drive";
    case DriveKind::current:
      return "a current-driven drive";
    case DriveKind::torque:
      return "a torque-driven drive";
  }
  return "a drive";
}

/// How `mcg-fit gap` tries an effect as a candidate: the parameters it sets free, a coarse
/// grid of starting values for each (the best grid point on the training cost starts the
/// fit), and what the training runs must contain to excite the effect at all.
struct EffectPlan {
  enum class Needs { nothing, clutch_engaged, clutch_engagement, both_directions };
  /// Where the effect acts, which decides the drives it can show under: on the shaft, a
  /// measurement or the command's timing (every drive); in the bridge or the motor's circuit,
  /// which an ideal current loop overrides (a voltage drive only); in the armature circuits
  /// of motor and generator (under a current or torque drive only through the generator's,
  /// so only where the engaged generator feeds a load).
  enum class Acts { anywhere, motor_circuit, circuits };
  bool candidate = true;                    ///< false: not tried as an added effect
  std::vector<std::string> free;            ///< effect parameter keys fitted
  std::vector<std::vector<double>> grid;    ///< per free key, starting values tried
  Needs needs = Needs::nothing;
  Acts acts = Acts::anywhere;
  /// A parameter that is a harmonic order of the motor angle (cogging's N_per_rev): its
  /// starting values are the strongest orders of the residual over the measured angle.
  std::string angle_order_key;
  /// Per free key, the factor the grid values are multiplied by for the given nominal
  /// parameters and the runs' drive (grids in units of the motor's and the drive's own size, e.g.
  /// the torque it can apply, so they fit any motor and drive); nullptr: the grid is absolute.
  std::vector<double> (*grid_scale)(const Params& nominal, const DriveScale& drive) = nullptr;
  /// Keys of param_mismatch the refit holds at 1 while this effect is in the model (they
  /// would move what the effect's own parameters move).
  std::vector<std::string> supersedes;
  /// Free keys that are a resistance in series with the armature (a bridge's switches): speed
  /// alone tells them from R no better than R_scale (see gap's mismatch_free), and beside a
  /// refitted Kt they trade with the viscous friction. Without a measured current they are
  /// held at 0: the given R then stands for the whole circuit.
  std::vector<std::string> series_resistance;
  /// A friction effect: tried before the others, and fitted on the regularised stick
  /// (SimOptions::smooth_stick), scored on the exact one.
  bool friction = false;
  /// Starting values of `free` (in its order) from the friction the data show, tried before
  /// the grid; an empty vector when the data do not determine them. nullptr: the grid only.
  std::vector<double> (*data_start)(const DataFriction& seen, const Params& nominal) = nullptr;
  /// The free key that sets a friction effect's breakaway level (empty: none). The regularised
  /// stick moves the response continuously in it, the exact stick-slip decides it: the search
  /// profiles it on the exact model after the fit (value and standard error).
  std::string breakaway_key;
  /// The discrepancy term shapes this effect's fit starts from when the catalog alone leaves
  /// the gap unexplained (the one owner of which shape is which effect's).
  std::vector<TermSeed> seeded_by;

  static EffectPlan fit(std::vector<std::string> free, std::vector<std::vector<double>> grid,
                        Needs needs = Needs::nothing, std::string angle_order_key = {}) {
    EffectPlan plan;
    plan.free = std::move(free);
    plan.grid = std::move(grid);
    plan.needs = needs;
    plan.angle_order_key = std::move(angle_order_key);
    return plan;
  }
  /// This plan as a friction effect's, started from the data by `start` when given.
  EffectPlan as_friction(std::vector<double> (*start)(const DataFriction&, const Params&) = nullptr) && {
    friction = true;
    data_start = start;
    return std::move(*this);
  }
  /// This plan, started from discrepancy terms of the shapes of `seeds` as well.
  EffectPlan seeded_by_terms(std::vector<TermSeed> seeds) && {
    seeded_by = std::move(seeds);
    return std::move(*this);
  }
  /// This plan with its grid scaled by `scale` (grid_scale).
  EffectPlan scaled_by(std::vector<double> (*scale)(const Params&, const DriveScale&)) && {
    grid_scale = scale;
    return std::move(*this);
  }
  /// This plan with `keys` of its free keys a series resistance (series_resistance).
  EffectPlan in_series(std::vector<std::string> keys) && {
    series_resistance = std::move(keys);
    return std::move(*this);
  }
  /// This plan for an effect that acts where `where` says (Acts).
  EffectPlan acting_in(Acts where) && {
    acts = where;
    return std::move(*this);
  }
  /// True when the effect can show under `drive`; `generator_loaded`: some run engages the
  /// generator on a load (its armature circuit carries a current whatever drives the motor).
  bool applies_to(DriveKind drive, bool generator_loaded) const {
    if (drive == DriveKind::voltage || acts == Acts::anywhere) return true;
    return acts == Acts::circuits && generator_loaded;
  }
  static EffectPlan not_a_candidate() {
    EffectPlan plan;
    plan.candidate = false;
    return plan;
  }
};

/// One entry of the effect catalog: one module under model/effects/ defines it whole.
struct EffectSpec {
  std::string name;
  std::string summary;    ///< one line
  std::string equation;   ///< the physics, plain text
  std::vector<EffectParamSpec> params;
  /// Resolves the effect into the plant's hooks (model/effects/compiled.hpp).
  void (*compile)(const Effect& effect, Compiled& plant) = nullptr;
  EffectPlan plan;
};

/// The catalog, in the order of its registry (model/effects/catalog.cpp).
const std::vector<EffectSpec>& effect_catalog();
/// The spec of effect `name`, or nullptr.
const EffectSpec* find_effect(std::string_view name);
/// The catalog as `mcg-sim --list-effects` prints it: per effect two `#` lines (summary,
/// equation), then one tab-separated row per parameter: effect, parameter, unit, default,
/// min, max, meaning (under a header row of those names).
void write_effect_catalog(std::ostream& out);
/// The catalog as the EFFECTS entries of mcg-sim(1), in roff: per effect a tagged paragraph
/// naming it, each parameter with its default, range and unit, what it is and its equation.
void write_effect_catalog_roff(std::ostream& out);
/// The tail of a message about an unknown effect name: the nearest name of the catalog (of
/// its diagnosis candidates only, when `candidates_only`) if it is close, and where to look.
std::string unknown_effect_hint(std::string_view name, bool candidates_only = false);
/// An effect with all parameters at their defaults. Throws mcg::Error for an unknown name.
Effect default_effect(std::string_view name);
/// Parses "NAME" or "NAME:key=value,key=value". Unknown names/keys, malformed numbers and
/// values outside the bounds throw mcg::Error "<where>: ...: '<bad text>'".
Effect parse_effect(std::string_view text, std::string_view where = "--effect");
/// "NAME:key=value,..." with every parameter, numbers in shortest exact form.
std::string format_effect(const Effect& effect);

/// A torque on the motor shaft outside the catalog, T = basis(k, theta, omega) with the
/// term's coefficient in k[3] by convention: what the gap diagnosis' discrepancy fit found,
/// or an effect a test makes that the catalog does not have.
struct ShaftTerm {
  std::string equation;  ///< how it reads, e.g. "0.0012 N m sin(11 theta + 0.3)"
  double (*basis)(const std::array<double, 4>& k, double theta_rad, double omega_rad_s) = nullptr;
  std::array<double, 4> k{};
  /// Used instead of `basis` when set: a term that also depends on the motor current i_A
  /// (torque ripple, load-dependent friction) or on the time t_s (a level that drifts).
  double (*basis_it)(const std::array<double, 4>& k, double theta_rad, double omega_rad_s, double i_A,
                     double t_s) = nullptr;
};

/// The model: nominal parameters plus active effects (each name at most once).
struct Model {
  Params params = builtin_rig();
  std::vector<Effect> effects;
  std::vector<ShaftTerm> shaft_terms;

  const Effect* effect(std::string_view name) const;
};

/// Reads parameters and effects ([effect.NAME] sections with the effect's keys) from `ini`.
Model model_from_ini(const config::Ini& ini, Model base = Model{});
void model_to_ini(const Model& model, config::Ini& ini);

/// One named, bounded parameter of a model, for fitting.
struct ParamInfo {
  std::string name;   ///< "motor.R_ohm", "clutch_engaged.Tc_Nm", "stribeck.v_s_rad_s", ...
  double value;
  double lower;
  double upper;
  std::string unit;
  double period = 0.0;  ///< EffectParamSpec::period; 0 for a bounded parameter
};

/// The nominal parameters (named "section.key" as in the INI form, e.g. "motor.J_kg_m2",
/// "motor.Kt_Nm_A", "motor.Tc_Nm", "motor.c1", "drive.dead_time_s") followed by every
/// parameter of the active effects ("EFFECT.key"), with their fitting bounds: relative to the
/// given model for the nominal ones; the catalog range for an effect's, widened for a level in
/// N m to twice the motor's stall torque Kt supply_V / R (in N m s/rad to that per no-load
/// speed supply_V / Ke) when that is larger.
std::vector<ParamInfo> parameters(const Model& model);
/// Why `value` is not a valid value of parameter `name` ("must be a finite number > 0", "out of
/// range [0, 0.05]"), by the same rules the INI form checks; nullopt when it is, or for a name
/// the model does not know (set_parameter() refuses those).
std::optional<std::string> parameter_problem(const Model& model, std::string_view name, double value);
/// Sets one parameter by its name; throws mcg::Error for an unknown name.
void set_parameter(Model& model, std::string_view name, double value);
/// Reads one parameter by its name; throws mcg::Error for an unknown name.
double get_parameter(const Model& model, std::string_view name);

/// Open circuit on the generator terminals.
inline constexpr double k_open_circuit = std::numeric_limits<double>::infinity();

/// What drives the plant over one step: the commanded average bridge voltage (or an ideal
/// current loop's command), the clutch state and the generator load.
struct Drive {
  double v_V = 0.0;                       ///< commanded average voltage, duty * supply_V
  int clutch = 2;                         ///< 0, 1 or 2
  double r_load_ohm = k_open_circuit;     ///< >= 0, inf = relay open
  /// A current-driven drive's command, A: an ideal current loop holds i_A = i_cmd_A, so the
  /// motor circuit is not integrated and v_V is ignored (NaN: a voltage drive). The state's
  /// v_applied_V is then the circuit's drop R i + drop(i) + Ke w (L di/dt not modelled).
  double i_cmd_A = std::numeric_limits<double>::quiet_NaN();
};

/// The plant's state at one instant (S: double, or Dual with its sensitivities).
template <class S>
struct BasicState {
  double t_s = 0.0;
  S omega_rad_s = 0.0;      ///< motor shaft speed
  S omega_gen_rad_s = 0.0;  ///< generator shaft speed (= motor when rigidly engaged; 0 in state 0)
  S theta_rad = 0.0;        ///< motor shaft angle since the start
  S theta_gen_rad = 0.0;    ///< generator shaft angle since the start
  S i_A = 0.0;              ///< motor armature current
  S i_gen_A = 0.0;          ///< generator current (through winding and r_load)
  S v_gen_V = 0.0;          ///< generator terminal voltage: r_load i_gen, or Ke w_g when open
  S v_applied_V = 0.0;      ///< average voltage at the motor terminals (after delay, bridge effects)
  S temp_rise_K = 0.0;      ///< motor winding temperature rise (thermal effect)
  int clutch = 2;
  bool stuck = true;  ///< motor shaft held by static friction
};
using State = BasicState<double>;

/// Integrator settings.
struct SimOptions {
  /// Largest step, s. The circuits' decay is taken exactly (plant.cpp), so L/R does not
  /// bound it; the clutch spring's period does, a torque ripple's period at the speed of the
  /// moment (up to ripple_speed_rad_s), and under the brush drop or a shaft torque of unknown
  /// shape half the fastest electrical time constant (L/R = 1.05 ms for the rig's motor: 524 us).
  double max_step_s = 1e-3;
  /// Fastest motor speed a torque ripple's period is resolved at, rad/s (0: the no-load speed
  /// supply_V / Ke): the step follows the speed up to it. A fit takes 1.2 times a measured
  /// run's fastest speed (fit::simulate_as_measured), so a fit's trial that runs away (a
  /// current drive without friction) is not stepped for speeds the rig never reached.
  double ripple_speed_rad_s = 0.0;
  /// Also resolve each circuit whose decay spans steps or a good part of a row: half its L/R
  /// (524 us for the rig's motor, L/R = 1.05 ms). A step's first stage takes the current
  /// before an input's change, so a decay of a few steps would be integrated into the speed
  /// coarsely, and the regularised stick's breakaway between two drive levels moves with Ts
  /// only through the current's rise. A decay over within a quarter of the largest step and
  /// of the rows' interval (a 100:1 gearmotor's 0.1 ms; a 73:1 gearmotor's 0.5 ms logged at
  /// 100 Hz) is taken exactly and bounds the step only to a sixteenth of the motor's
  /// mechanical time constant J R / (Kt Ke). The fits keep it; mcg-sim's runs drop it (within
  /// 0.005 rpm RMS).
  bool circuit_bound = true;
  /// Regularised stick, for fitting friction: a stuck motor shaft breaks away at a rate that
  /// grows exponentially with its drive torque, e-fold per 1 % of Ts (plant.cpp,
  /// k_stick_width), rather than at the instant the torque passes Ts. On the exact stick-slip
  /// any static level between two levels of a staircase gives the same run, and a fit locks
  /// onto a level's edge; here the run moves with Ts continuously. The generator stays exact.
  bool smooth_stick = false;
};

class PlantImpl;

/// The plant, stepped in time: fixed-step (exponential) RK4 between events, with the zero crossings of the
/// speeds and the breakaway instants located inside a step (so stick-slip does not chatter or
/// creep), row inputs held over each step. Copyable (a copy is an independent snapshot).
class Plant {
 public:
  explicit Plant(const Model& model, const SimOptions& options = {}, int initial_clutch = 2);
  ~Plant();
  Plant(const Plant& other);
  Plant& operator=(const Plant& other);
  Plant(Plant&&) noexcept;
  Plant& operator=(Plant&&) noexcept;

  /// Before the first step: the motor shaft turning at omega_rad_s (the generator's with it
  /// when the clutch is engaged), the currents at zero, as a capture that starts mid-run found
  /// the rig.
  void start_at(double omega_rad_s);
  /// Advances by dt_s > 0 with `drive` held over [t, t + dt_s). A clutch change takes effect
  /// at the start of the step.
  void step(double dt_s, const Drive& drive);
  State state() const;
  double time_s() const;

 private:
  PlantImpl* m_impl;
};

/// Open-loop inputs, one entry per row; row n acts over [t_s[n], t_s[n+1]).
struct Inputs {
  std::vector<double> t_s;
  std::vector<double> v_V;
  std::vector<double> clutch;       ///< 0, 1, 2
  std::vector<double> r_load_ohm;   ///< >= 0 or inf
  /// A current-driven drive (Drive::i_cmd_A), A; empty: a voltage drive.
  std::vector<double> i_cmd_A;
  /// A torque-driven drive: the drive torque at the motor shaft, N m, commanded as the current
  /// T / Kt of the simulated model; empty: not torque-driven. At most one of the two is set.
  std::vector<double> T_cmd_Nm;
};

/// Outputs, one entry per row: the state at t_s[n] (before row n's inputs act).
struct Outputs {
  std::vector<double> omega_rad_s;
  std::vector<double> rpm;          ///< true speed, 60 w / (2 pi)
  std::vector<double> theta_rad;
  std::vector<double> omega_gen_rad_s;
  std::vector<double> i_A;
  std::vector<double> i_gen_A;
  std::vector<double> v_gen_V;
  std::vector<double> v_applied_V;

  void resize(std::size_t rows);
  void store(std::size_t row, const State& state);
};

/// Simulates the rows of `inputs` from rest at t_s[0] (initial clutch = clutch[0]).
/// Inputs are validated by the caller (increasing finite t, finite v, clutch 0/1/2, r_load >= 0);
/// stops (MCG_DEMAND) otherwise.
Outputs simulate(const Model& model, const Inputs& inputs, const SimOptions& options = {});

/// Checks `inputs` like mcg-sim does; throws mcg::Error naming `source` and the row's line
/// (line = first_line + row) for the first bad value.
void validate_inputs(const Inputs& inputs, std::string_view source, std::size_t first_line);

}  // namespace mcg::model
