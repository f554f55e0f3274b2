// Friction identification from slow ramp or staircase runs (mcg-fit friction), with the
// report's stacking: motor alone; plus the clutch attached; plus the clutch engaged and
// the generator.
#pragma once

#include <array>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "fit/greybox.hpp"
#include "model/model.hpp"
#include "table/table.hpp"

namespace mcg::fit {

/// A jump of v by more than this between rows is a step of the drive, V (a slow ramp moves it
/// by millivolts a row).
inline constexpr double k_friction_jump_V = 0.05;
/// On a current or torque drive, a jump of the command by more than this share of its largest
/// magnitude (and far beyond its row-to-row noise: drive_jump) is a step.
inline constexpr double k_friction_jump_share = 0.05;

struct FrictionOptions {
  /// Order of the viscous polynomial P(x) = c1 x + ... + c_order x^order (1..3).
  int order = 3;
  /// Samples closer than settle_s after a jump of the drive's command (DriveInput: v, or a
  /// current or torque drive's own column) larger than `jump` (or a change of clutch or r_load)
  /// are transients and skipped; a slow ramp never jumps.
  double settle_s = 0.15;
  /// In the command's unit (V; A; the torque column's). Unset: k_friction_jump_V on a voltage
  /// drive; on a current or torque drive drive_jump()'s with k_friction_jump_share.
  std::optional<double> jump;
  /// Length of the averaging windows in the quasi-steady stretches, s.
  double window_s = 0.1;
  /// Use the measured current `i` where the run has it (else the voltage balance).
  bool use_current = true;
  /// Estimate the static level from starts from rest. Off for runs that never rest (a
  /// closed loop that keeps the shaft moving): then Ts is reported equal to Tc.
  bool static_friction = true;
  /// What drives the rig, as mcg-fit model and gap read it (DriveInput, its one owner): a
  /// current-driven drive's `i` is the drive torque Kt i whatever use_current says; a
  /// torque-driven drive's column (N m at the measured shaft; N on a linear axis), e.g. a force
  /// computed by a current-driven amplifier's controller, is the motor's torque column /
  /// gear ratio (no machine constant needed). Such runs need no v.
  DriveInput drive;
  /// Column holding the measured position (rad; m on a linear axis): the speed is its central
  /// difference (with_speed_from_position, as model and gap take it) instead of a measured
  /// rpm/omega.
  std::string position_column;
  /// Estimate the inertia (kg m^2; kg on a linear axis) with the friction: the windows are
  /// regressed on the mean acceleration too, instead of subtracting J dw/dt with J from
  /// the configuration.
  bool fit_inertia = false;
  /// Estimate a constant drive bias (N m; N) with the friction: a load that does not change
  /// sign with the direction (gravity on an inclined axis, an amplifier offset).
  bool offset = false;
  /// Motor turns per turn of the shaft whose speed (or position) was measured: the model's
  /// `[measurement] gear_ratio` (`gear_ratio` of the INI) and a command's override; a run's
  /// `# gear_ratio:` metadata states its own (measurement::settle_gear_ratio). The friction is
  /// that of the motor shaft: its speed is the measured one times the ratio.
  std::optional<double> gear_ratio_ini;
  std::optional<double> gear_ratio_override;
  /// Share of the PWM off-time in which the driver lets the motor coast (the model's
  /// pwm_coast.coast; 0: a braking driver): the voltage balance's back-emf acts only while the
  /// current flows, Kt (v - (1 - coast (1 - |v| / supply_V)) Ke w) / R.
  double coast = 0.0;
};

/// A friction element and the standard errors of its values (same layout).
struct FrictionTerm {
  model::Friction value;
  model::Friction se;
};

/// What the runs in one clutch state show: the total friction on the motor shaft.
///   moving windows: T_f = mean(T_drive) - J_shaft dw/dt - T_gen_load, regressed on
///                   sign(w) (Tc + c1 |w| + ... + c_order |w|^order), standard errors the
///                   larger of OLS and a jackknife over the stretches (fit_inertia: J dw/dt is a regressor,
///                   not subtracted; offset: a constant regressor too); dw/dt = (w_end - w_start) / window,
///                   so the window mean of J dw/dt is exact without differentiating twice;
///   T_drive       = Kt i (measured current) or Kt (v - Ke w) / R (voltage balance, the
///                   armature at steady state: L di/dt averages out over a window; behind a
///                   coasting driver Kt (v - (1 - coast (1 - |v| / supply_V)) Ke w) / R);
///   T_gen_load    = Kt_g i_gen, or Kt_g Ke_g w / (R_g + r_load) (state 2 only);
///   breakaway     = each start from rest: Ts lies between the largest drive torque held
///                   at rest and the drive torque when the shaft moved; Ts is the mean of the
///                   midpoints, its standard error combines their spread and the bracket
///                   width / sqrt(12).
struct StateFriction {
  int clutch = 0;
  FrictionTerm total;
  std::size_t windows = 0;
  std::size_t breakaways = 0;
  double omega_min_rad_s = 0.0;  ///< speed range of the moving windows (|w|)
  double omega_max_rad_s = 0.0;
  bool from_current = false;  ///< every window used the measured current
  double inertia = std::numeric_limits<double>::quiet_NaN();     ///< fit_inertia: J (kg m^2, or kg)
  double inertia_se = std::numeric_limits<double>::quiet_NaN();
  double offset = std::numeric_limits<double>::quiet_NaN();      ///< offset: constant bias (N m, or N)
  double offset_se = std::numeric_limits<double>::quiet_NaN();
  /// Quasi-steady stretches (split at most 2 s long) the windows come from.
  std::size_t blocks = 0;
  /// Standard errors of the regressed values (Tc, c1 .. c_order, then inertia and offset when
  /// fitted) two ways: the windows' OLS, which takes them as independent, and a delete-one-block
  /// jackknife over the stretches, which sees what a stretch's windows share (NaN when there
  /// are fewer than 5 blocks or one block alone carries a needed speed). The reported errors
  /// (total.se, inertia_se, offset_se) are the larger of the two.
  std::vector<double> se_ols;
  std::vector<double> se_jackknife;
};

/// The stacked elements (standard errors add in quadrature):
///   motor             = total(state 0)
///   clutch_disengaged = total(state 1) - motor
///   clutch_engaged    = total(state 2) - motor - generator, generator = motor (the report's
///                       "equivalent systems" assumption).
/// The report subtracted only the motor for its "clutch engaged" row (207.5 mA - 89 mA), so
/// that row still contains the generator, which its Simulink model then adds a second time;
/// subtracting both makes the model's sum reproduce the measured total.
/// When no state-0 run is given, the motor's friction is taken from `base` (se 0).
struct FrictionResult {
  std::vector<StateFriction> states;  ///< in clutch order, only states present in the runs
  std::optional<FrictionTerm> motor;  ///< estimated (state 0 present)
  std::optional<FrictionTerm> clutch_disengaged;
  std::optional<FrictionTerm> clutch_engaged;
  model::Params params;  ///< `base` with the estimated frictions (and generator = motor) written in
};

/// Estimates the frictions from runs with columns t, v (or duty), clutch, r_load, rpm (or
/// omega) and optionally i (and i_gen in state 2). Throws mcg::Error naming the file or the
/// clutch state for: a missing column, too few rows, a state whose shaft never leaves
/// stiction, no start from rest (static friction unknown), or too few distinct speeds for
/// the polynomial ("no excitation in the needed range").
FrictionResult fit_friction(const std::vector<table::Table>& runs, const model::Params& base,
                            const FrictionOptions& options = {});

}  // namespace mcg::fit
