// friction_levels: Coulomb, static and viscous friction on the motor shaft beyond the
// model's own, as additive levels. A model given without friction (or with too little) has
// nothing for param_mismatch's scales to multiply; this adds it, with exact stick-slip
// through the plant's friction (not a torque term). The diagnosis starts the levels at
// fractions of the torque the drive can apply (a voltage drive's stall torque Kt supply_V / R,
// a multiple of a current drive's Kt i_max or a torque drive's largest torque, DriveScale):
// Coulomb 0.2 %, 1 %, 4 %, from a
// precision motor's bearings to a gearmotor's brushes and seals; static excess 0.1 % and 1 %;
// the viscous level at 0.1 % and 1 % of that torque per the drive's speed (the no-load speed
// supply_V / Ke, or the fastest the runs turn), so the grid fits any motor and drive. The starts
// are not 0: the fit moves positive levels in log coordinates, by ratios.
#include <algorithm>

#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

void compile(const Effect& e, Compiled& c) {
  Friction& f = c.p.motor.friction;
  f.Tc_Nm += e.get("Tc_Nm");
  f.Ts_Nm += e.get("Tc_Nm") + e.get("Ts_excess_Nm");
  f.viscous[0] += e.get("c1_Nm_s_rad");
}

std::vector<double> stall_scale(const Params& p) {
  const double stall_Nm = p.motor.Kt_Nm_A * p.supply_V / p.motor.R_ohm;
  const double no_load_rad_s = p.supply_V / p.motor.Ke_V_s_rad;
  return {stall_Nm, stall_Nm, stall_Nm / no_load_rad_s};
}

/// The grid's scale: the drive's torque, per its speed for the viscous level.
std::vector<double> drive_torque_scale(const Params& /*nominal*/, const DriveScale& drive) {
  return {drive.torque_Nm, drive.torque_Nm, drive.torque_Nm / drive.speed_rad_s};
}

/// The levels the data show, each at least 1e-4 of its motor-sized scale: the fit moves the
/// levels in log coordinates, so a start is positive.
std::vector<double> start_from_data(const DataFriction& seen, const Params& p) {
  const std::vector<double> scale = stall_scale(p);
  return {std::max(seen.coulomb_Nm, 1e-4 * scale[0]), std::max(seen.static_excess_Nm, 1e-4 * scale[1]),
          std::max(seen.viscous_Nm_s_rad, 1e-4 * scale[2])};
}

/// A level against the motion, c sign(w) with c < 0, is the added Coulomb level -c; the other
/// levels start at their floor (positive: the fit moves them by ratios).
std::vector<std::pair<std::string, double>> from_sign(const TermValues& t, const Params& p) {
  if (!(t.coefficient < 0.0)) return {};
  const std::vector<double> scale = stall_scale(p);
  return {{"Tc_Nm", -t.coefficient}, {"Ts_excess_Nm", 1e-4 * scale[1]}, {"c1_Nm_s_rad", 1e-4 * scale[2]}};
}

EffectPlan plan() {
  EffectPlan p = EffectPlan::fit({"Tc_Nm", "Ts_excess_Nm", "c1_Nm_s_rad"},
                                 {{0.002, 0.01, 0.04}, {0.001, 0.01}, {0.001, 0.01}})
                     .as_friction(start_from_data)
                     .seeded_by_terms({{TermShape::sign, from_sign}});
  p.grid_scale = drive_torque_scale;
  p.supersedes = {"coulomb_scale", "static_scale", "viscous_scale"};
  p.breakaway_key = "Ts_excess_Nm";
  return p;
}

}  // namespace

EffectSpec friction_levels() {
  return {
      "friction_levels",
      "Coulomb, static and viscous friction on the motor shaft beyond the model's own",
      "motor Tc += Tc_Nm, Ts += Tc_Nm + Ts_excess_Nm, c1 += c1_Nm_s_rad: F(w) = sign(w) (Tc + c1 |w| + ...) "
      "moving, held up to Ts at rest",
      {{"Tc_Nm", 1e-3, 0.0, 10.0, "N m", "added Coulomb level"},
       {"Ts_excess_Nm", 0.0, 0.0, 10.0, "N m", "added static level above the added Coulomb level"},
       {"c1_Nm_s_rad", 0.0, 0.0, 1.0, "N m s/rad", "added viscous coefficient"}},
      compile,
      plan()};
}

}  // namespace mcg::model::effects
