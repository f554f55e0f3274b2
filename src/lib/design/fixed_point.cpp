// Q-format choice and quantisation of the controller's coefficients.
#include "design/fixed_point.hpp"

#include "common/error.hpp"
#include "config/ini.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace mcg::design {

std::string FixedPoint::q_format(int coef_bits) const { return fmt::format("Q{}.{}", coef_bits - 1 - frac_bits, frac_bits); }

FixedPoint quantise(const std::vector<double>& b0, const std::vector<double>& a0, const FixedPointSpec& spec) {
  if (a0.empty() || a0[0] == 0.0) fail("fixed point: a_0 must be non-zero");
  if (spec.coef_bits < 2 || spec.coef_bits > 32) fail("fixed point: coefficient bits must be in 2..32, got {}", spec.coef_bits);
  if (spec.acc_bits < spec.coef_bits || spec.acc_bits > 63) {
    fail("fixed point: accumulator bits must be in {}..63, got {}", spec.coef_bits, spec.acc_bits);
  }
  if (!(spec.e_max_counts > 0.0)) fail("fixed point: e_max_counts must be positive");
  if (!(spec.out_min < spec.out_max)) fail("fixed point: out_min must be below out_max");
  std::vector<double> b = b0;
  std::vector<double> a = a0;
  for (double& x : b) x /= a0[0];
  for (double& x : a) x /= a0[0];
  const double coef_max = std::ldexp(1.0, spec.coef_bits - 1) - 1.0;
  const double acc_limit = std::ldexp(1.0, spec.acc_bits - 1) - 1.0;
  const double y_max = std::max(std::abs(spec.out_min), std::abs(spec.out_max));
  double biggest = 0.0;
  for (double x : b) biggest = std::max(biggest, std::abs(x));
  for (std::size_t k = 1; k < a.size(); ++k) biggest = std::max(biggest, std::abs(a[k]));
  int f = spec.coef_bits - 1;
  if (biggest > 0.0) f = std::min(f, static_cast<int>(std::floor(std::log2(coef_max / biggest))) + 1);
  for (; f >= 0; --f) {
    const double scale = std::ldexp(1.0, f);
    bool fits = true;
    double acc = f > 0 ? std::ldexp(1.0, f - 1) : 0.0;
    FixedPoint q;
    q.frac_bits = f;
    for (double x : b) {
      const double v = std::round(x * scale);
      fits = fits && std::abs(v) <= coef_max;
      acc += std::abs(v) * spec.e_max_counts;
      q.b_q.push_back(static_cast<std::int64_t>(v));
    }
    q.a_q.push_back(static_cast<std::int64_t>(scale));
    for (std::size_t k = 1; k < a.size(); ++k) {
      const double v = std::round(a[k] * scale);
      fits = fits && std::abs(v) <= coef_max;
      acc += std::abs(v) * y_max;
      q.a_q.push_back(static_cast<std::int64_t>(v));
    }
    if (!fits || acc > acc_limit) continue;
    q.acc_max = acc;
    for (std::size_t k = 0; k < b.size(); ++k) {
      if (b[k] != 0.0 && q.b_q[k] == 0) {
        fail("fixed point: b{} = {} rounds to 0 in {} (widen the coefficients or lower e_max_counts)", k,
             config::format_number(b[k]), q.q_format(spec.coef_bits));
      }
      q.b.push_back(static_cast<double>(q.b_q[k]) / scale);
    }
    for (std::size_t k = 0; k < a.size(); ++k) {
      if (a[k] != 0.0 && q.a_q[k] == 0) {
        fail("fixed point: a{} = {} rounds to 0 in {} (widen the coefficients or lower e_max_counts)", k,
             config::format_number(a[k]), q.q_format(spec.coef_bits));
      }
      q.a.push_back(static_cast<double>(q.a_q[k]) / scale);
    }
    return q;
  }
  fail("fixed point: no Q format keeps {}-bit coefficients and a {}-bit accumulator from overflowing for |e| <= {} "
       "counts and y in [{}, {}]",
       spec.coef_bits, spec.acc_bits, config::format_number(spec.e_max_counts), config::format_number(spec.out_min),
       config::format_number(spec.out_max));
}

}  // namespace mcg::design
