// friction_asymmetry: the motor shaft's friction differs by direction (brush angle, bearing
// preload, a lead screw's load; every real motor tried showed it). Moving forward the
// kinetic and static levels are Tc + dT and Ts + dT, in reverse Tc - dT and Ts - dT. That is
// the symmetric friction plus a constant torque -dT on the shaft, moving or stuck, so the
// plant's torque hook carries it with exact stick-slip. |dT| beyond the friction levels is a
// constant load (gravity on an arm), which the same equation describes, and so is a drive's
// constant bias (an amplifier's or current sensor's offset: the torque acting is the logged one
// minus dT): this is the one parameter of that constant, fit::k_drive_offset, which a friction
// fit's offset estimates too.
// Default 0.5 mN m, a fifth of the rig's Coulomb level; the diagnosis starts from a tenth to
// twice that level, either sign, scaled by the torque the drive can apply over the rig's stall
// torque (model::builtin_grid_scale), so that a larger motor or a current drive starts alike.
#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

template <class S>
S bias(const std::array<S, 4>& k, S /*theta_rad*/, S /*omega_rad_s*/) {
  return -k[0];
}

void compile(const Effect& e, Compiled& c) {
  c.motor_torque.push_back({bias<double>, {e.get("dT_Nm"), 0.0, 0.0, 0.0}, nullptr, 0.0, bias<Dual>});
}

/// The asymmetry the data show, when the runs move both ways.
std::vector<double> start_from_data(const DataFriction& seen, const Params& /*nominal*/) {
  if (!seen.both_directions) return {};
  return {seen.asymmetry_Nm};
}

std::vector<double> grid_scale(const Params& nominal, const DriveScale& drive) {
  return builtin_grid_scale("T", nominal, drive);
}

}  // namespace

EffectSpec friction_asymmetry() {
  return {"friction_asymmetry",
          "the motor shaft's friction is higher in one direction than the other",
          "forward F = Tc + dT (breakaway Ts + dT), reverse F = Tc - dT (Ts - dT): the symmetric friction "
          "plus a constant torque -dT on the motor shaft",
          {{"dT_Nm", 5e-4, -0.05, 0.05, "N m",
            "half the forward-minus-reverse friction level; a drive's constant bias or load"}},
          compile,
          EffectPlan::fit({"dT_Nm"}, {{-0.005, -0.0015, -0.0003, 0.0003, 0.0015, 0.005}},
                          EffectPlan::Needs::both_directions)
              .as_friction(start_from_data)
              .scaled_by(grid_scale)};
}

}  // namespace mcg::model::effects
