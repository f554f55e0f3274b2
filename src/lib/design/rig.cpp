// Linearisation of the rig model at an operating point.
#include "design/rig.hpp"

#include "common/error.hpp"
#include "linsys/c2d.hpp"

#include <Eigen/Dense>

#include <cmath>

namespace mcg::design {

namespace {

/// dF/dω of the kinetic friction at ω0 > 0: c1 + 2 c2 ω0 + 3 c3 ω0².
double slope(const model::Friction& f, double w) { return f.viscous[0] + w * (2.0 * f.viscous[1] + 3.0 * w * f.viscous[2]); }

}  // namespace

linsys::Tf linearise_rig(const model::Params& p, int clutch, double w0, double r_load) {
  if (clutch < 0 || clutch > 2) fail("--clutch: must be 0, 1 or 2, got {}", clutch);
  if (!(w0 > 0.0) || !std::isfinite(w0)) fail("--speed: the operating speed must be positive, got {} rad/s", w0);
  if (!(r_load >= 0.0)) fail("--r-load: must be >= 0 (inf = open), got {}", r_load);
  const model::Machine& m = p.motor;
  const model::Machine& g = p.generator;
  double b = slope(m.friction, w0);
  double j = m.J_kg_m2;
  if (clutch == 1) b += slope(p.clutch_disengaged, w0);
  const bool coupled = clutch == 2;
  if (coupled) {
    b += slope(p.clutch_engaged, w0) + slope(g.friction, w0);
    j += g.J_kg_m2;
  }
  const bool loaded = coupled && std::isfinite(r_load);
  const int n = loaded ? 3 : 2;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd bv = Eigen::VectorXd::Zero(n);
  Eigen::RowVectorXd c = Eigen::RowVectorXd::Zero(n);
  const int iw = n - 1;
  a(0, 0) = -m.R_ohm / m.L_H;
  a(0, iw) = -m.Ke_V_s_rad / m.L_H;
  bv(0) = 1.0 / m.L_H;
  a(iw, 0) = m.Kt_Nm_A / j;
  a(iw, iw) = -b / j;
  if (loaded) {
    a(1, 1) = -(g.R_ohm + r_load) / g.L_H;
    a(1, iw) = g.Ke_V_s_rad / g.L_H;
    a(iw, 1) = -g.Kt_Nm_A / j;
  }
  c(iw) = 1.0;
  linsys::Tf tf;
  tf.den = linsys::charpoly(a);
  tf.num = linsys::ss_numerator(a, bv, c);
  tf.delay_s = p.dead_time_s;
  return tf;
}

}  // namespace mcg::design
