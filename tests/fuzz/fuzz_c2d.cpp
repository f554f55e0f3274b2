// c2d (zero-order hold) against an independent oracle. The input bytes draw a continuous G:
// degree 1..8, poles and zeros real or in complex pairs, stable or not, repeated or not, with
// magnitudes 10^-1.5..10^1.5 rad/s, a gain 10^-3..10^3 and dt 10^-6..1 s. The oracle realises
// the same coefficients in long double (companion form, diagonally balanced), takes
// e^([[A B],[0 0]]·T) by Taylor series with scaling and squaring, and evaluates
// D(z) = det(zI − Φ) and N(z) = D(z)·(C(zI − Φ)^−1 Γ + d) on the unit circle. Where c2d answers,
// its N_p/D_p must agree: |N_p·D_o − N_o·D_p| <= k_tolerance·max|N_o|·max|D_o| at every point
// (numerator and denominator each right to 1e-5 of their size on the circle). A refusal
// (mcg::Error) is always allowed.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "fuzz.hpp"
#include "linsys/c2d.hpp"
#include "linsys/poly.hpp"

namespace {

using Ld = long double;
using Cld = std::complex<Ld>;
using MatL = Eigen::Matrix<Ld, Eigen::Dynamic, Eigen::Dynamic>;
using MatC = Eigen::Matrix<Cld, Eigen::Dynamic, Eigen::Dynamic>;
using VecC = Eigen::Matrix<Cld, Eigen::Dynamic, 1>;

constexpr double k_tolerance = 1e-5;

/// Reads the fuzzer's bytes as numbers; past the end every read is 0.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  unsigned byte() { return pos_ < size_ ? data_[pos_++] : 0U; }
  /// A fraction in [0, 1] from two bytes.
  double unit() {
    const unsigned hi = byte();
    return static_cast<double>(hi * 256U + byte()) / 65535.0;
  }
  double log_uniform(double lo_exp, double hi_exp) {
    return std::pow(10.0, lo_exp + (hi_exp - lo_exp) * unit());
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

/// Roots in conjugate pairs: `count` of them, each real or a pair, stable or not, or a repeat.
std::vector<std::complex<double>> draw_roots(Bytes& in, int count) {
  std::vector<std::complex<double>> r;
  while (static_cast<int>(r.size()) < count) {
    const unsigned kind = in.byte();
    const bool room_for_pair = static_cast<int>(r.size()) + 2 <= count;
    if ((kind & 3U) == 3U && !r.empty()) {  // a repeat of the last root (or pair)
      const auto last = r.back();
      if (last.imag() != 0.0 && room_for_pair) {
        r.push_back(std::conj(last));
        r.push_back(last);
      } else if (last.imag() == 0.0) {
        r.push_back(last);
      } else {
        r.push_back(last.real());
      }
      continue;
    }
    const double mag = in.log_uniform(-1.5, 1.5);
    const double sign = (kind & 4U) != 0U && (kind & 8U) != 0U ? 1.0 : -1.0;  // a quarter unstable
    if ((kind & 1U) != 0U && room_for_pair) {
      const double angle = std::numbers::pi / 2.0 * in.unit();
      r.emplace_back(sign * mag * std::cos(angle), mag * std::sin(angle));
      r.emplace_back(sign * mag * std::cos(angle), -mag * std::sin(angle));
    } else {
      r.emplace_back(sign * mag, 0.0);
    }
  }
  return r;
}

/// e^M by Taylor series with scaling and squaring, in long double.
MatL expm(const MatL& m) {
  const Ld norm = m.cwiseAbs().colwise().sum().maxCoeff();
  int squarings = 0;
  if (norm > 0.25L) squarings = static_cast<int>(std::ceil(std::log2(norm / 0.25L)));
  const MatL x = m * std::ldexp(1.0L, -squarings);
  MatL e = MatL::Identity(m.rows(), m.cols());
  MatL term = e;
  for (int k = 1; k <= 40; ++k) {
    term = (term * x) / static_cast<Ld>(k);
    e += term;
  }
  for (int i = 0; i < squarings; ++i) e = e * e;
  return e;
}

struct Oracle {
  std::vector<Cld> n;  // N_o at the points
  std::vector<Cld> d;  // D_o at the points
};

Oracle oracle(const mcg::linsys::Poly& num, const mcg::linsys::Poly& den, double dt,
              const std::vector<Cld>& z) {
  const auto nd = static_cast<Eigen::Index>(den.size()) - 1;
  const Ld lead = static_cast<Ld>(den[0]);
  std::vector<Ld> a(den.size());
  for (std::size_t i = 0; i < den.size(); ++i) a[i] = static_cast<Ld>(den[i]) / lead;
  std::vector<Ld> b(den.size(), 0.0L);  // num padded to den's length, over den's lead
  for (std::size_t i = 0; i < num.size(); ++i)
    b[den.size() - num.size() + i] = static_cast<Ld>(num[i]) / lead;
  const Ld dd = b[0];  // the direct term (a is monic)
  // Controllable canonical form: x1' = −Σ a_(j+1) x_j + u, x_(i+1)' = x_i; y = Σ c_j x_j + dd·u.
  MatL m = MatL::Zero(nd + 1, nd + 1);
  for (Eigen::Index j = 0; j < nd; ++j) m(0, j) = -a[static_cast<std::size_t>(j) + 1];
  for (Eigen::Index i = 1; i < nd; ++i) m(i, i - 1) = 1.0L;
  m(0, nd) = 1.0L;
  std::vector<Ld> c(static_cast<std::size_t>(nd));
  for (std::size_t j = 0; j < c.size(); ++j) c[j] = b[j + 1] - dd * a[j + 1];
  // Osborne balancing of the A block by powers of two: x = S x̃ keeps the system, improves e^A.
  std::vector<Ld> s(static_cast<std::size_t>(nd), 1.0L);
  for (int sweep = 0; sweep < 60; ++sweep) {
    bool changed = false;
    for (Eigen::Index i = 0; i < nd; ++i) {
      Ld row = 0.0L;
      Ld col = 0.0L;
      for (Eigen::Index j = 0; j < nd; ++j) {
        if (j == i) continue;
        row += std::abs(m(i, j));
        col += std::abs(m(j, i));
      }
      if (row == 0.0L || col == 0.0L) continue;
      Ld f = 1.0L;
      while (col * f * f < row / 4.0L) f *= 2.0L;
      while (col * f * f > row * 4.0L) f /= 2.0L;
      if (f == 1.0L) continue;
      changed = true;
      m.block(0, i, nd, 1) *= f;  // column i of A by f, row i of [A B] by 1/f
      m.block(i, 0, 1, nd + 1) /= f;
      s[static_cast<std::size_t>(i)] *= f;
    }
    if (!changed) break;
  }
  const MatL e = expm(m * static_cast<Ld>(dt));
  const MatC phi = e.topLeftCorner(nd, nd).cast<Cld>();
  const VecC gamma = e.topRightCorner(nd, 1).cast<Cld>();
  Oracle out;
  for (const Cld& zk : z) {
    MatC r = -phi;
    r.diagonal().array() += zk;
    const Eigen::PartialPivLU<MatC> lu(r);
    const VecC x = lu.solve(gamma);
    Cld h = dd;
    for (Eigen::Index j = 0; j < nd; ++j)
      h += c[static_cast<std::size_t>(j)] * s[static_cast<std::size_t>(j)] * x(j);
    const Cld det = lu.determinant();
    out.d.push_back(det);
    out.n.push_back(det * h);
  }
  return out;
}

Cld eval_ld(const mcg::linsys::Poly& p, Cld z) {
  Cld acc = 0.0L;
  for (const double x : p) acc = acc * z + static_cast<Ld>(x);
  return acc;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Bytes in(data, size);
  const int n = 1 + static_cast<int>(in.byte() % 8U);
  const int m = static_cast<int>(in.byte() % static_cast<unsigned>(n + 1));
  const double dt = in.log_uniform(-6.0, 0.0);
  const double gain = (in.byte() & 1U ? -1.0 : 1.0) * in.log_uniform(-3.0, 3.0);
  const auto poles = draw_roots(in, n);
  const auto zeros = draw_roots(in, m);
  mcg::linsys::Tf g;
  g.den = mcg::linsys::from_roots(poles);
  g.num = mcg::linsys::scale(mcg::linsys::from_roots(zeros), gain);
  mcg::linsys::Tf h;
  try {
    h = mcg::linsys::c2d(g, dt, mcg::linsys::C2dMethod::zoh, 0.0, "--plant");
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
    return 0;
  }
  if (!h.discrete() || h.dt_s != dt || h.delay_s != 0.0)
    mcg::fuzz::finding("c2d did not answer a z-domain H");
  const int points = 2 * n + 5;
  std::vector<Cld> z;
  for (int k = 0; k < points; ++k) {
    z.push_back(std::polar(1.0L, 2.0L * std::numbers::pi_v<Ld> * (k + 0.17L) / points));
  }
  const Oracle o = oracle(g.num, g.den, dt, z);
  // Both sides monic in the denominator.
  const Ld lead = static_cast<Ld>(mcg::linsys::trim(h.den).at(0));
  Ld n_max = 0.0L;
  Ld d_max = 0.0L;
  for (int k = 0; k < points; ++k) {
    n_max = std::max(n_max, std::abs(o.n[static_cast<std::size_t>(k)]));
    d_max = std::max(d_max, std::abs(o.d[static_cast<std::size_t>(k)]));
  }
  for (int k = 0; k < points; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    const Cld np = eval_ld(h.num, z[kk]) / lead;
    const Cld dp = eval_ld(h.den, z[kk]) / lead;
    const Ld err = std::abs(np * o.d[kk] - o.n[kk] * dp);
    if (!(err <= static_cast<Ld>(k_tolerance) * n_max * d_max)) {
      std::fprintf(stderr, "fuzz_c2d: at point %d the error is %Lg of max|N|·max|D| (dt %g, degree %d/%d)\n",
                   k, err / (n_max * d_max), dt, m, n);
      mcg::fuzz::finding("c2d's zoh disagrees with the long-double state-space oracle");
    }
  }
  return 0;
}
