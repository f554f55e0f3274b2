// Controller design, solved exactly on the loop's frequency response: P, PI, PID, lead, lag,
// root locus for a damping ratio, and a robust automatic tuning.
#pragma once

#include "linsys/analysis.hpp"
#include "linsys/c2d.hpp"
#include "linsys/tf.hpp"

#include <string>
#include <utility>
#include <vector>

namespace mcg::design {

using linsys::Complex;
using linsys::Tf;

/// What a controller is designed for. `plant` is the loop without the controller, in s or z.
/// With dt_s > 0 the controller runs sampled: its continuous form C(s) is discretised by
/// `method` and the design is solved on the loop the board really runs, C_d(e^(jωT))·P.
struct Setup {
  Tf plant;
  double dt_s = 0.0;
  linsys::C2dMethod method = linsys::C2dMethod::tustin;
  double prewarp_rad_s = 0.0;
};

/// A designed controller: its continuous transfer function and named parameters.
struct Design {
  std::string kind;  ///< p, pi, pid, lead, lag
  Tf cont;           ///< C(s)
  std::vector<std::pair<std::string, double>> params;
  double wc_rad_s = 0.0;  ///< the crossover the design aimed at
};

/// The controller that runs: C(s), or its discretisation when setup.dt_s > 0.
Tf running_form(const Setup& setup, const Tf& cont);
/// The loop's factors {running controller, plant} for analysis.
std::vector<Tf> loop_factors(const Setup& setup, const Tf& cont);

/// P for a phase margin: ω_c is the lowest frequency where arg P = −180° + PM (mod 360°),
/// found by bisection on the exactly unwrapped phase; Kp = 1/|P(jω_c)|.
Design design_p(const Setup& setup, double pm_deg);

/// PI C = Kp (s + ω_z)/s = Kp + Ki/s (Ki = Kp ω_z) with the zero ω_z given: ω_c is the lowest
/// frequency where the loop phase is −180° + PM; Kp = 1/|loop(jω_c)|.
Design design_pi_zero(const Setup& setup, double pm_deg, double zero_rad_s);
/// PI with the crossover ω_c given: the zero is solved so the phase at ω_c is −180° + PM.
/// Throws when a PI (0° .. −90° at ω_c) cannot supply it.
Design design_pi_crossover(const Setup& setup, double pm_deg, double wc_rad_s);

/// PID with a filtered derivative, C = Kp (1 + 1/(Ti s) + Td s/(1 + Td s/N)), Ti = ratio·Td:
/// the smallest Td that gives the phase margin at ω_c, then Kp for crossover at ω_c.
Design design_pid(const Setup& setup, double pm_deg, double wc_rad_s, double ti_over_td, double n);

/// The board's PID (mcg-protocol(7): U[n] = U[n-1] + b0 e[n] + b1 e[n-1] + b2 e[n-2]), designed in
/// z at setup.dt_s: no derivative filter, integral and derivative by backward differences,
/// C(z) = Kp (1 + (T/Ti) z/(z - 1) + (Td/T) (z - 1)/z), Ti = ratio·Td: the smallest Td that gives
/// the phase margin at ω_c, then Kp for crossover at ω_c.
Design design_pid_board(const Setup& setup, double pm_deg, double wc_rad_s, double ti_over_td);

/// Lead C = K (1 + s/ω_z)/(1 + s/ω_p), ω_z = ω_c√α, ω_p = ω_c/√α, α = (1 − sin φ)/(1 + sin φ),
/// with the lead φ solved so that PM holds at ω_c exactly (also through a discretisation).
Design design_lead(const Setup& setup, double pm_deg, double wc_rad_s);

/// Lag C = K0 (1 + s/ω_z)/(1 + s/ω_p) with DC gain K0, ω_z = ω_c/ratio, ω_p = ω_z/β: ω_c and β
/// solved together so that |loop(jω_c)| = 1 and the phase margin is met exactly.
Design design_lag(const Setup& setup, double pm_deg, double k_dc, double ratio);

/// Root-locus design: the smallest gain K > 0 that puts closed-loop poles of 1 + K·P on the
/// damping line ζ (s = ω_n(−ζ + j√(1 − ζ²)), in z its image e^(sT)).
struct RlocusResult {
  Design design;
  double omega_n_rad_s = 0.0;
  std::vector<Complex> poles;
};
RlocusResult design_rlocus(const Setup& setup, double zeta);

/// Limits of the automatic tuning.
struct TuneLimits {
  double pm_min_deg = 45.0;
  double gm_min_db = 6.0;
  double ms_max = 1.7;
};
/// Peak sensitivity Ms = max_ω |1/(1 + L(jω))| of the loop `factors`.
double peak_sensitivity(const std::vector<Tf>& factors, double* omega_rad_s = nullptr);
/// True when the loop meets the limits: closed loop stable, every phase margin >= pm_min,
/// every gain margin at least gm_min dB from 0 dB, Ms <= ms_max.
bool meets(const Setup& setup, const Tf& cont, const TuneLimits& limits);
/// Automatic robust tuning of a P or PI ("p", "pi"): the highest crossover ω_c for which some
/// controller of the family (Kp from |L(jω_c)| = 1; PI zero ω_z = ρ ω_c, ρ from 1 down to 0.01)
/// meets the limits; among those at the best ω_c, the largest ρ (most integral action).
Design tune(const Setup& setup, const std::string& structure, const TuneLimits& limits);

}  // namespace mcg::design
