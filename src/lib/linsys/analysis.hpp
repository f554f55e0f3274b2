// Loop analysis: margins by root finding on the frequency response, closed-loop poles,
// the stable range of a root-locus gain.
#pragma once

#include "linsys/tf.hpp"

#include <limits>
#include <vector>

namespace mcg::linsys {

/// Every crossover of an open loop L and the margins of unity negative feedback.
/// Gain crossovers ω_gc: |L(jω_gc)| = 1; phase margin PM = 180° + arg L(jω_gc), wrapped to
/// (−180°, 180°]; delay margin DM = PM[rad]/ω_gc (only where PM > 0). Phase crossovers ω_pc:
/// arg L(jω_pc) = −180° (mod 360°); gain margin GM = 1/|L(jω_pc)|. For z, jω means e^(jωT)
/// and ω runs up to the Nyquist frequency π/T. The headline values are MATLAB's choice: the GM
/// nearest to 1 (0 dB), the PM nearest to 0, the smallest DM; ±inf/nan where there is none.
struct Margins {
  std::vector<double> gain_crossovers_rad_s;
  std::vector<double> phase_margins_deg;
  std::vector<double> delay_margins_s;
  std::vector<double> phase_crossovers_rad_s;
  std::vector<double> gain_margins;
  double gm = std::numeric_limits<double>::infinity();
  double gm_omega_rad_s = std::numeric_limits<double>::quiet_NaN();
  double pm_deg = std::numeric_limits<double>::infinity();
  double pm_omega_rad_s = std::numeric_limits<double>::quiet_NaN();
  double dm_s = std::numeric_limits<double>::infinity();
};

/// Finds all crossovers of a proper loop by scanning a dense grid (logarithmic, plus linear
/// steps of π/(4·delay) for a delay, dense near every lightly damped root) and refining each
/// sign change of ln|L| and of the exactly unwrapped phase by bisection to machine precision.
/// Throws mcg::Error for an improper loop.
Margins margins(const Tf& loop);
/// Margins of the product of `factors`, each evaluated in its own domain at the same ω: a
/// discrete controller C(e^(jωT)) in series with a continuous plant P(jω) that already holds
/// the sampling lag (the report's way). Any discrete factor limits ω to π/T.
Margins margins(const std::vector<Tf>& factors);

/// ln|L|, unwrapped arg L and L itself for a product of factors in s and/or z.
class LoopEval {
 public:
  explicit LoopEval(const std::vector<Tf>& factors);
  double log_mag(double omega_rad_s) const;
  double phase_rad(double omega_rad_s) const;
  Complex value(double omega_rad_s) const;
  const std::vector<FreqEval>& factors() const { return m_factors; }
  /// Sample period of the discrete factors (0 if none).
  double dt_s() const { return m_dt_s; }
  double delay_s() const;
  /// Scan range holding every crossover.
  void range(double& lo_rad_s, double& hi_rad_s) const;

 private:
  std::vector<FreqEval> m_factors;
  double m_dt_s = 0.0;
};

/// Closed-loop poles of L/(1 + L). A continuous delay uses its [6/6] Padé approximant
/// (`padded` says so); a discrete delay is exact (z^−k).
std::vector<Complex> closed_loop_poles(const Tf& loop, bool* padded = nullptr);
/// The closed loop L/(1 + L) is stable, by roots_stable() of its characteristic polynomial (a
/// continuous delay as in closed_loop_poles()); throws mcg::Error when double precision cannot
/// decide it.
bool closed_loop_stable(const Tf& loop);
/// All poles strictly inside the left half-plane (s) or the unit circle (z).
bool is_stable(const std::vector<Complex>& poles, Domain domain);

/// A range of gains K > 0 for which 1 + K·L = 0 has all roots stable.
struct GainRange {
  double k_low = 0.0;
  double k_high = std::numeric_limits<double>::infinity();
};

/// Exact stable ranges of a root-locus gain K multiplying L: the boundary gains are −1/L at
/// the phase crossovers (and at ω = 0, π/T where L is real), each interval classified by its
/// closed-loop poles. For a discrete loop the upper end of the first range is the gain at
/// which the locus leaves the unit circle.
std::vector<GainRange> stable_gain_ranges(const Tf& loop);

/// Boundary gains of stable_gain_ranges (sorted, positive).
std::vector<double> boundary_gains(const Tf& loop);

/// The dense frequency grid margins() scans for `le`: logarithmic over le.range(), fine near
/// lightly damped roots, linear steps of π/(4·delay) with a delay.
std::vector<double> scan_frequencies(const LoopEval& le);

/// Log-spaced grid of n >= 2 frequencies from lo to hi (rad/s).
std::vector<double> log_grid(double lo, double hi, int n);

/// A default frequency range for plots and scans of `g`: three decades either side of its
/// corner frequencies, up to π/T in z.
void default_range(const Tf& g, double& lo_rad_s, double& hi_rad_s);

}  // namespace mcg::linsys
