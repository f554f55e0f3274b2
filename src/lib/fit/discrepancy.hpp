// The shape of what the model misses, found without the catalog: sparse regression of the
// torque residual the measured speed implies on a library of candidate terms.
//
// Method. Along each run the measured speed w (at the motor, rad/s) and angle theta (its
// integral) drive the model's own equations: the armature current i follows
//   L di/dt = v - R i - Ke w              (exact over each sample; the measured i when there is one)
// and the model's torque on the moving shaft is T = Kt i - F(w) - T_gen(w), with the friction
// and inertia of the clutch state. Over windows [a, b] of 20 ms in which the shaft moves,
// the torque the model lacks satisfies (weak form: no derivative of a noisy speed)
//   J (w(b) - w(a)) - int_a^b T dt = sum_k xi_k int_a^b phi_k dt.
// The library phi_k: a constant, sign(w), w, w|w|, w^3, Stribeck-like drops
// sign(w) exp(-|w|/w_s) and sign(w) exp(-(w/w_s)^2) at two speed scales, friction levels
// fading as exp(-t/tau), |i| sign(w), Kt i, sin and cos of the angle once per revolution and at
// the strongest orders of the speed residual (plain and times i), and the voltage side as the
// torque it costs: a drop against the current and a dead band of the drive (inertia is a
// nominal parameter: the refit's). A counting estimator's half-window lag is taken out of the
// measured speed first. Forward stepwise sparse regression on the training runs adds one term
// at a time while each removes a clear share of the residual (k_discrepancy_threshold), stands
// clear of 0 and lowers the validation residual too, so of collinear terms only one joins. The
// terms, added to the model as shaft torques, are simulated on the validation runs and kept
// only where the speed gap shrinks there, then refitted jointly with the nominal scales and the
// model's catalog effects (discrepancy_joint.cpp), the joint model kept when the held-out runs
// gain again.
// Beside the shaft (discrepancy_side.cpp): where the current is measured, the armature
// circuit's own weak form (a current reading's gain and offset, told from a resistance and a
// constant voltage by the torque equation, which sees a reading's error too; a brush drop; a
// dead band; a back-emf error), and the speed reading's offset, gain and error periodic in the
// angle, tried after the shaft terms and before them, the order that leaves the held-out runs
// clearly less winning.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fit/gap.hpp"

namespace mcg::fit {

/// A term joins when it removes at least this share of the torque residual the model leaves
/// (||y||^2) and stands at least three standard errors from 0.
inline constexpr double k_discrepancy_threshold = 0.05;
/// Fewest windows of the weak form the fit runs on.
inline constexpr std::size_t k_discrepancy_min_windows = 40;
/// Window of the weak form, s.
inline constexpr double k_discrepancy_window_s = 0.02;

/// Fits the discrepancy of `reference` on the training runs of `data` and scores it on the
/// validation runs (speed must be measured). `angle_orders`: the orders of the motor angle
/// the library's harmonics use.
/// `stop`: asked during the joint refit, true ends it there (a time budget).
DiscrepancyResult fit_discrepancy(const model::Model& reference, const GapData& data,
                                  const std::vector<double>& angle_orders,
                                  const std::vector<OutputFloor>& floors,
                                  const std::function<bool()>& stop = {});

/// What the surviving terms explain, each part in its own domain, for the report: the torque
/// terms' share of the torque residual (training and validation), the circuit and current
/// reading terms' share of the motor circuit's voltage residual, what correcting the current
/// reading removes of the torque residual, and the validation rpm RMS before and after.
/// `summary`: the one-line form of the CSV metadata (validation only, 3 and 4 digits). Speeds
/// in `unit`.
std::string explained_text(const DiscrepancyResult& d, bool summary, const SpeedUnit& unit = {});

/// Term `t` as the report gives it in the data's speed `unit`: a speed reading's equation names
/// the measured column (omega_measured = omega (1 + ...)), and its offset (held in rpm, as the
/// fit's residual) is converted, with its error and unit. Other terms are returned as they are.
DiscrepancyTerm in_speed_unit(DiscrepancyTerm t, const SpeedUnit& unit);

/// The verdict's ", closing 85 % of the rest": what the terms close of the speed gap above
/// the noise; when the terms that survive act beside the shaft without moving the simulated
/// speed (the circuit, the current reading), what they close in their own domain.
std::string closing_text(const DiscrepancyResult& d);

/// Catalog effects whose shape a surviving term has, started from the term's values: each
/// effect's plan names the term shapes it starts from and how (EffectPlan::seeded_by, e.g. an
/// angle harmonic at two or more cycles a revolution -> cogging, a level against the motion ->
/// friction_levels, |i| sign(w) -> friction_load, a drop against the current -> brush_drop, a
/// voltage lost in the drive's direction -> hbridge), values clamped to the parameters' ranges;
/// each term starts at most one effect. Effects `reference` already has are left out.
std::vector<model::Effect> catalog_seeds(const DiscrepancyResult& result, const model::Model& reference);

}  // namespace mcg::fit
