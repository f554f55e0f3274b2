// Transfer functions in s or z, with a pure delay, and their exact frequency response.
#pragma once

#include "linsys/poly.hpp"

#include <string>
#include <vector>

namespace mcg::linsys {

enum class Domain { s, z };

/// G = num/den · e^(−s·delay_s), in s (continuous) or z (sampled every dt_s). In z a delay is
/// a whole number of samples (fold_delay() turns it into z^−k). Coefficients are in
/// descending powers, as typed; no normalisation or cancellation happens behind the user.
struct Tf {
  Poly num{1.0};
  Poly den{1.0};
  Domain domain = Domain::s;
  double dt_s = 0.0;
  double delay_s = 0.0;

  bool discrete() const { return domain == Domain::z; }
  /// num(x)/den(x), no delay.
  Complex eval(Complex x) const;
  /// G(jω) or G(e^(jωT)) including the delay e^(−jω·delay_s); ω in rad/s.
  Complex freq(double omega_rad_s) const;
  /// deg num <= deg den.
  bool proper() const;
  bool strictly_proper() const;
  /// G(0) or G(1) (delay has unit gain): ±inf with a pole there, nan for 0/0.
  double dc_gain() const;
};

/// The highest degree a numerator or denominator may reach, typed or listed or made by a delay of
/// z^−k: far above any plant of the rig, low enough that roots and responses stay fast (a
/// 256×256 companion matrix). Beyond it the tools stop with an error, not a long run out of memory.
inline constexpr int k_max_degree = 256;
/// Throws mcg::Error "<what>: degree N above the limit of 256" when num or den is above k_max_degree.
void check_degree(const Tf& g, const std::string& what);
/// A delay as a number of samples, delay_s/dt_s, checked to be finite and at most `room`
/// (what is left of k_max_degree for z^−k); throws mcg::Error naming `what` otherwise, so the
/// caller may convert it to an integer safely.
double delay_samples(double delay_s, double dt_s, int room, const std::string& what);

/// The name of the variable: "s" or "z".
const char* var_name(Domain d);
/// a·b (domains and sample periods must agree; throws mcg::Error otherwise).
Tf series(const Tf& a, const Tf& b);
/// k·g.
Tf scaled(const Tf& g, double k);
/// Removes common roots at the origin (s^k or z^k in both num and den).
Tf cancel_origin(Tf g);
/// For z: multiplies den by z^k where k = delay_s/dt_s (throws if not a whole number of
/// samples, naming `what`); returns g with delay_s = 0. For s: returns g unchanged.
Tf fold_delay(const Tf& g, const std::string& what);
/// Unity negative feedback: T = L/(1+L). Requires no delay (fold it first in z).
Tf feedback(const Tf& loop);
/// The continuous delay e^(−sτ) as an order-n Padé approximant.
Tf pade(double delay_s, int order);

/// Text of a polynomial in `var`: "1.6194e-05*s^2 + 0.016437*s + 1".
std::string poly_text(const Poly& p, const char* var);
/// Text of a transfer function: "(num)/(den)" and "*exp(-0.002*s)" for a delay.
std::string tf_text(const Tf& g);
/// Coefficients as a space-separated list for INI values.
std::string list_text(const std::vector<double>& v);

/// Factored evaluation of G on the imaginary axis or the unit circle: magnitude as a product
/// of distances to the roots and the phase unwrapped exactly as the sum of the angles from
/// each zero minus each pole, minus ω·delay. Continuous in ω except where a root lies on the
/// axis (circle) itself.
class FreqEval {
 public:
  explicit FreqEval(const Tf& g);
  /// ln|G|.
  double log_mag(double omega_rad_s) const;
  /// Unwrapped arg G in rad.
  double phase_rad(double omega_rad_s) const;
  Complex value(double omega_rad_s) const { return m_tf.freq(omega_rad_s); }
  const std::vector<Complex>& zeros() const { return m_zeros; }
  const std::vector<Complex>& poles() const { return m_poles; }
  const Tf& tf() const { return m_tf; }
  /// Characteristic frequencies, rad/s: |root| in s, |ln root|/T in z (roots at 0 or the origin skipped).
  std::vector<double> corner_frequencies() const;

 private:
  Complex point(double omega_rad_s) const;
  Tf m_tf;
  std::vector<Complex> m_zeros;
  std::vector<Complex> m_poles;
  double m_log_k = 0.0;
  double m_arg_k = 0.0;
};

}  // namespace mcg::linsys
