// Continuous to discrete: zero- and first-order hold, Tustin, matched pole-zero, impulse invariant.
#pragma once

#include "linsys/tf.hpp"

#include <Eigen/Dense>

#include <string>

namespace mcg::linsys {

enum class C2dMethod { zoh, foh, tustin, matched, impulse };

/// "zoh", "foh", "tustin", "matched", "impulse".
const char* method_name(C2dMethod m);
/// Parses a method name; throws "<where>: unknown discretisation method 'x' (...)".
C2dMethod parse_method(const std::string& text, const std::string& where);

/// A state-space realisation x' = Ax + Bu, y = Cx + Du (SISO).
struct StateSpace {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::RowVectorXd c;
  double d = 0.0;
};

/// Controllable canonical realisation of a proper num/den (the delay is ignored), balanced
/// by a diagonal similarity so that wide-spread pole magnitudes keep their accuracy.
StateSpace realise(const Tf& g);
/// Characteristic polynomial det(xI − A), monic, via the Hessenberg form.
Poly charpoly(const Eigen::MatrixXd& a);
/// Numerator of C (xI − A)^(−1) B = det(xI − A + BC) − det(xI − A).
Poly ss_numerator(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, const Eigen::RowVectorXd& c);

/// Discretises a proper continuous G with sample period dt_s.
///  zoh:     H(z) = (1 − z^−1) Z{G(s)/s}, exact through exp([[A B],[0 0]]·T); a delay
///           τ = dT + θ (0 <= θ < T) is exact too: H = z^−(d+1)[z·N0 + N1 + D·den]/den with
///           Γ0 = ∫0^(T−θ) e^(Aσ)dσ·B and Γ1 = e^(A(T−θ))∫0^θ e^(Aσ)dσ·B.
///  foh:     triangle hold, H(z) = (z − 1)²/(T z) Z{G(s)/s²}.
///  tustin:  s = (2/T)(z − 1)/(z + 1), or with prewarp ω_p: s = ω_p/tan(ω_p T/2)·(z − 1)/(z + 1),
///           so that H(e^(jω_p T)) = G(jω_p).
///  matched: poles and zeros mapped by z = e^(sT), n − m − 1 zeros at infinity to z = −1 (one
///           stays, keeping a strictly proper G strictly proper), gain matched at DC after
///           removing the roots at s = 0 (z = 1).
///  impulse: H(z) = T·Z{g(kT)} for strictly proper G.
/// Delays other than ZOH's must be whole samples (then z^−k). prewarp_rad_s = 0: none.
/// The holds' denominator is Π(z − e^(p·T)) over G's poles; their numerator is refused
/// ("cannot be discretised accurately") where two evaluations of the sampled system disagree.
/// Throws mcg::Error naming `what` for an improper G or a bad delay.
Tf c2d(const Tf& g, double dt_s, C2dMethod method, double prewarp_rad_s, const std::string& what);

}  // namespace mcg::linsys
