// cogging: position-dependent torque ripple on the motor shaft. Default 1 mN m at 14 per
// revolution, the least common multiple of 7 slots and 2 poles of the usual small-motor
// armature. The diagnosis starts amplitudes from a quarter to the whole Coulomb level (the
// rig's, scaled by the torque the drive can apply over the rig's stall torque), eight phases,
// and the orders the residual's spectrum over the measured angle shows strongest.
#include <numbers>

#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

/// T = T_c sin(N theta + phase), k = {T_c, N, phase}.
template <class S>
S ripple(const std::array<S, 4>& k, S theta_rad, S /*omega_rad_s*/) {
  using std::sin;
  return k[0] * sin(k[1] * theta_rad + k[2]);
}

void compile(const Effect& e, Compiled& c) {
  const double N = e.get("N_per_rev");
  c.motor_torque.push_back(
      {ripple<double>, {e.get("T_c_Nm"), N, e.get("phase_rad"), 0.0}, nullptr, N, ripple<Dual>});
}

/// An angle harmonic of the shaft torque, at two or more cycles a revolution: cogging repeats
/// with the slots and poles; once per revolution is an imbalance or an eccentric load, which
/// cogging would only imitate.
std::vector<std::pair<std::string, double>> from_harmonic(const TermValues& t, const Params& /*nominal*/) {
  if (t.order < 2.0) return {};
  return {{"T_c_Nm", t.coefficient}, {"N_per_rev", t.order}, {"phase_rad", t.phase_rad}};
}

std::vector<double> grid_scale(const Params& nominal, const DriveScale& drive) {
  return builtin_grid_scale("T1", nominal, drive);
}

}  // namespace

EffectSpec cogging() {
  return {
      "cogging",
      "position-dependent torque ripple on the motor shaft",
      "T_cog = T_c sin(N theta + phase), theta = motor angle since the start; shifts breakaway too",
      {{"T_c_Nm", 1e-3, 0.0, 0.02, "N m", "amplitude"},
       {"N_per_rev", 14.0, 1.0, 200.0, "1/rev", "cycles per revolution"},
       {"phase_rad", 0.0, -std::numbers::pi, std::numbers::pi, "rad", "phase at theta = 0",
        2.0 * std::numbers::pi}},
      compile,
      EffectPlan::fit({"T_c_Nm", "phase_rad"},
                      {{0.0006, 0.001, 0.0016, 0.0025}, {-2.75, -1.96, -1.18, -0.39, 0.39, 1.18, 1.96, 2.75}},
                      EffectPlan::Needs::nothing, "N_per_rev")
          .scaled_by(grid_scale)
          .seeded_by_terms({{TermShape::angle_harmonic, from_harmonic}})};
}

}  // namespace mcg::model::effects
