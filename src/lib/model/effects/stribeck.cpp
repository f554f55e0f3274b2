// stribeck: kinetic friction falls from the static level to the Coulomb level over a
// velocity scale. Default v_s 10 rad/s (about 3 % of the rig's no-load speed), shape 1.5
// between Tustin's exponential (1) and the Gaussian form (2). The diagnosis starts v_s from
// slow creep (2 rad/s) to a tenth of the no-load speed, with the classical shapes 1 and 2
// (speeds the rig's, scaled by the drive's speed over the rig's no-load speed).
#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

/// The excess over the Coulomb level, (Ts - Tc) exp(-(x/v_s)^shape), k = {v_s, shape}; at
/// x <= 0 (inside a stage) its limit at 0+.
template <class S>
S excess(const std::array<S, 4>& k, const BasicFriction<S>& f, S x, S /*load_Nm*/) {
  using std::exp;
  using std::pow;
  if (x > 0.0) return (f.Ts_Nm - f.Tc_Nm) * exp(-pow(x / k[0], k[1]));
  return f.Ts_Nm - f.Tc_Nm;
}

void compile(const Effect& e, Compiled& c) {
  c.friction_terms.push_back(
      {excess<double>, nullptr, {e.get("v_s_rad_s"), e.get("shape_exp"), 0.0, 0.0}, excess<Dual>, nullptr});
}

std::vector<double> grid_scale(const Params& nominal, const DriveScale& drive) {
  return builtin_grid_scale("w1", nominal, drive);
}

}  // namespace

EffectSpec stribeck() {
  return {"stribeck",
          "kinetic friction falls from the static level to the Coulomb level over a velocity scale",
          "every friction element: F(w) = sign(w) [Tc + (Ts - Tc) exp(-(|w|/v_s)^shape_exp) + P(|w|)]; "
          "breakaway level Ts unchanged",
          {{"v_s_rad_s", 10.0, 0.1, 200.0, "rad/s", "Stribeck velocity"},
           {"shape_exp", 1.5, 0.5, 3.0, "1", "exponent of the Stribeck curve"}},
          compile,
          EffectPlan::fit({"v_s_rad_s", "shape_exp"}, {{2.0, 5.0, 12.0, 30.0, 80.0}, {1.0, 2.0}})
              .as_friction()
              .scaled_by(grid_scale)};
}

}  // namespace mcg::model::effects
