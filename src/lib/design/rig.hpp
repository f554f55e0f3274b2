// The rig model (src/lib/model) linearised at an operating point: a plant for mcg-design.
#pragma once

#include "common/units.hpp"  // rad_s_from_rpm, k_pi: the operating point and frequencies
#include "linsys/tf.hpp"
#include "model/model.hpp"

namespace mcg::design {

/// Small-signal ω/v (rad/s per V) of the rig at clutch state 0, 1 or 2, speed ω0 > 0 and
/// generator load r_load (inf = open), from the states x = [i, i_gen, ω]:
///   L  di/dt     = v − R i − Ke ω
///   Lg di_gen/dt = Ke_g ω − (R_g + r_load) i_gen          (state 2 with a finite load only)
///   J  dω/dt     = Kt i − Kt_g i_gen − b ω,   b = dF/dω at ω0
/// F is the kinetic friction on the shaft (motor; + disengaged clutch in state 1; + engaged
/// clutch and generator in state 2) and J the inertia it turns (Jm, or Jm + Jg when engaged).
/// Coulomb friction only sets the operating point. The drive's dead time becomes the delay.
/// Throws mcg::Error for a bad state or speed.
linsys::Tf linearise_rig(const model::Params& p, int clutch, double omega0_rad_s, double r_load_ohm);

}  // namespace mcg::design
