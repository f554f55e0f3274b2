// Fixed-point coefficients for the board's difference equation (docs/formats.md, [fixed_point]).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace mcg::design {

/// The integer arithmetic the firmware runs each tick n (all integers):
///   acc = Σ_k b_q[k]·e[n−k] − Σ_{k>=1} a_q[k]·y[n−k]           (acc_bits-bit accumulator)
///   y[n] = clamp((acc + 2^(F−1)) >> F, out_min, out_max)          (F = frac_bits, F = 0: no rounding term)
/// with c_q = round(c·2^F) for the real coefficients normalised to a_0 = 1, each in a signed
/// coef_bits-bit word; e in [−e_max, e_max] counts, y the stored (clamped) output.
struct FixedPointSpec {
  int coef_bits = 16;
  int acc_bits = 32;
  double e_max_counts = 32767.0;
  double out_min = -922.0;
  double out_max = 922.0;
};

struct FixedPoint {
  int frac_bits = 0;
  std::vector<std::int64_t> b_q;
  std::vector<std::int64_t> a_q;  ///< a_q[0] = 2^F
  std::vector<double> b;          ///< b_q/2^F: the coefficients that really run
  std::vector<double> a;
  double acc_max = 0.0;           ///< worst-case |acc| over the stated ranges
  /// "Q4.11": integer bits (sign excluded) and fraction bits of a coefficient word.
  std::string q_format(int coef_bits) const;
};

/// Chooses the largest F for which every coefficient fits a signed coef_bits word and the
/// worst-case accumulator Σ|b_q|·e_max + Σ_{k>=1}|a_q|·max(|out_min|, |out_max|) + 2^(F−1)
/// fits a signed acc_bits word. Throws mcg::Error when no F >= 0 fits, or when a non-zero
/// coefficient would round to 0 (the controller would change structure).
FixedPoint quantise(const std::vector<double>& b, const std::vector<double>& a, const FixedPointSpec& spec);

}  // namespace mcg::design
