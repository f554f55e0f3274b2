// Discretisation of continuous transfer functions.
#include "linsys/c2d.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <optional>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "common/error.hpp"
#include "config/ini.hpp"

namespace mcg::linsys {

namespace {

/// Whole samples and the fraction θ of τ = d·T + θ; d is at most `room` (checked, so that the
/// z^−d the caller multiplies in stays within k_max_degree).
void split_delay(double delay_s, double dt_s, int room, const std::string& what, long& whole, double& theta_s) {
  const double samples = delay_samples(delay_s, dt_s, room, what);
  double d = std::floor(samples + 1e-9);
  double theta = delay_s - d * dt_s;
  if (theta < 1e-9 * dt_s) theta = 0.0;
  whole = static_cast<long>(d);
  theta_s = theta;
}

Tf make_z(Poly num, Poly den, double dt_s, long delay_samples) {
  Tf h;
  h.domain = Domain::z;
  h.dt_s = dt_s;
  const Poly d = trim(den);
  const double lead = d.front();
  h.num = scale(trim(num), 1.0 / lead);
  h.den = mul(scale(d, 1.0 / lead), monomial(static_cast<int>(delay_samples)));
  return cancel_origin(h);
}

long whole_delay(const Tf& g, double dt_s, const std::string& what, const char* method) {
  long d = 0;
  double theta = 0.0;
  split_delay(g.delay_s, dt_s, k_max_degree - degree(trim(g.den)), what, d, theta);
  if (theta != 0.0) {
    fail("{}: {} needs a delay of whole samples; {} s is not a multiple of {} s (use zoh)", what, method,
         config::format_number(g.delay_s), config::format_number(dt_s));
  }
  return d;
}

/// How far a numerator may disagree with its state-space system, relative to its largest value
/// on the unit circle, before c2d refuses it (see numerator()).
constexpr double k_numerator_tolerance = 1e-6;
/// Squarings more than needed in the exponential the numerator is checked against.
constexpr int k_check_squarings = 3;

/// det of an (n+1)×(n+1) matrix that is upper Hessenberg but for its dense last row and column,
/// by Gaussian elimination with partial pivoting in O(n²): below the diagonal of column k only
/// rows k + 1 and n can be nonzero, and so they stay (the pivots are those of a full LU).
Complex bordered_hessenberg_det(Eigen::MatrixXcd& b) {
  const Eigen::Index last = b.rows() - 1;
  Complex det(1.0, 0.0);
  for (Eigen::Index k = 0; k < last; ++k) {
    Eigen::Index p = k;
    if (k + 1 < last && std::abs(b(k + 1, k)) > std::abs(b(p, k))) p = k + 1;
    if (std::abs(b(last, k)) > std::abs(b(p, k))) p = last;
    if (p != k) {
      b.row(k).swap(b.row(p));
      det = -det;
    }
    const Complex pivot = b(k, k);
    if (pivot == Complex(0.0, 0.0)) return {0.0, 0.0};
    det *= pivot;
    auto eliminate = [&](Eigen::Index r) {
      const Complex f = b(r, k) / pivot;
      if (f != Complex(0.0, 0.0)) b.row(r).segment(k, last + 1 - k) -= f * b.row(k).segment(k, last + 1 - k);
    };
    if (k + 1 < last) eliminate(k + 1);
    eliminate(last);
  }
  return det * b(last, last);
}

/// A sampled system: Φ, the input column z·g0 + g1 of the bordered numerator, the direct term d.
struct Sampled {
  Eigen::MatrixXd phi;
  Eigen::VectorXd g0;
  Eigen::VectorXd g1;
  double d = 0.0;
};

/// The sampled system's denominator D(z) = Π (z − e^(p_i·T)) over the poles p_i of G: Φ's
/// eigenvalues mapped exactly. Not det(zI − Φ) expanded from Φ: with poles of e^(pT) from 0.5 to
/// 1e8 (unstable poles at a 1 s period) that expansion lost D's small coefficients (det Φ was 2e-5
/// wrong where e^(T·trace A) is exact); the mapped roots keep each coefficient to its rounding,
/// and a cluster (a repeated pole, split by the root finder) keeps its symmetric functions.
Poly sampled_denominator(const Poly& den, double dt_s, const std::string& what) {
  std::vector<Complex> mapped;
  for (const Complex& p : roots(den)) {
    mapped.push_back(std::exp(p * dt_s));
    if (!std::isfinite(std::abs(mapped.back()))) {
      fail("{}: e^(A*dt) overflows: a pole p with Re(p)*dt above 709 has no sampled value", what);
    }
  }
  Poly d = from_roots(mapped);
  for (double x : d) {
    if (!std::isfinite(x)) fail("{}: the sampled system's denominator overflows", what);
  }
  return d;
}

/// P(z) = D(z)·(C(zI − Φ)^−1(z·g0 + g1) + d), D = sampled_denominator(): the numerator over D of
/// the sampled system, of degree <= n. The bracket is det [[zI − Φ, z·g0 + g1], [−C, d]] over
/// det(zI − Φ), both from one Hessenberg form of Φ.
///
/// Not as det(zI − Φ + ΓC) − det(zI − Φ): for a short sample period ΓC is tiny beside Φ ≈ I
/// and that difference cancels to nothing (1/(s+1)^6 at 1 ms: a numerator of 1e-21 beside
/// coefficients of 20). Instead P is evaluated at n + 1 points of the unit circle, each by an LU
/// factorisation of the bordered matrix (backward stable, no difference of near-equal
/// polynomials), and its coefficients follow by the inverse DFT, which is perfectly conditioned
/// on the circle. n + 1 further points check the result: where P disagrees there with its
/// system by more than k_numerator_tolerance of max |P| the evaluation is not accurate enough
/// and c2d refuses it; coefficients below that noise are zero.
std::optional<Poly> numerator(const Sampled& sampled, const Sampled& check, const Eigen::RowVectorXd& c,
                              const Poly& den_z, const std::string& what, double& disagreement) {
  const Eigen::MatrixXd& phi = sampled.phi;
  const double d = sampled.d;
  const Eigen::Index n = phi.rows();
  disagreement = 0.0;
  if (n == 0) return trim(Poly{d});
  const std::size_t m = static_cast<std::size_t>(n) + 1;
  constexpr double k_two_pi = 2.0 * std::numbers::pi;
  // An offset that keeps the points off z = ±1, where integrators and Nyquist zeros sit.
  const double offset = 0.3 * k_two_pi / static_cast<double>(m);
  // Φ = Q·H·Qᵀ with H upper Hessenberg, once: the bordered matrix with H, Qᵀg and C·Q has the
  // same determinant (det Q² = 1), and its LU costs O(n²) a point instead of O(n³).
  Eigen::MatrixXd h = phi;
  Eigen::MatrixXd q = Eigen::MatrixXd::Identity(n, n);
  if (n > 2) {
    const Eigen::HessenbergDecomposition<Eigen::MatrixXd> hd(phi);
    h = hd.matrixH();
    q = hd.matrixQ();
  }
  const Eigen::VectorXcd g0q = (q.transpose() * sampled.g0).cast<Complex>();
  const Eigen::VectorXcd g1q = (q.transpose() * sampled.g1).cast<Complex>();
  const Eigen::RowVectorXcd cq = (c * q).cast<Complex>();
  Eigen::MatrixXcd b(n + 1, n + 1);
  auto value_at = [&](Complex z) {
    b.setZero();
    b.topLeftCorner(n, n) = -h.cast<Complex>();
    b.topLeftCorner(n, n).diagonal().array() += z;
    b(n, n) = 1.0;
    const Complex det_phi = bordered_hessenberg_det(b);
    b.setZero();
    b.topLeftCorner(n, n) = -h.cast<Complex>();
    b.topLeftCorner(n, n).diagonal().array() += z;
    b.topRightCorner(n, 1) = g0q * z + g1q;
    b.bottomLeftCorner(1, n) = -cq;
    b(n, n) = d;
    return eval(den_z, z) * (bordered_hessenberg_det(b) / det_phi);
  };
  auto angle = [&](std::size_t k, double shift) {
    return offset + shift + k_two_pi * static_cast<double>(k) / static_cast<double>(m);
  };
  std::vector<Complex> v(m);
  double v_max = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    v[k] = value_at(std::polar(1.0, angle(k, 0.0)));
    v_max = std::max(v_max, std::abs(v[k]));
  }
  if (!std::isfinite(v_max)) fail("{}: the sampled system's numerator overflows", what);
  // Ascending coefficients a_j = (1/m) sum_k v_k e^(−i j θ_k).
  Poly ascending(m, 0.0);
  for (std::size_t j = 0; j < m; ++j) {
    Complex acc(0.0, 0.0);
    for (std::size_t k = 0; k < m; ++k) acc += v[k] * std::polar(1.0, -angle(k, 0.0) * static_cast<double>(j));
    ascending[j] = acc.real() / static_cast<double>(m);
  }
  Poly p(ascending.rbegin(), ascending.rend());
  double residual = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    const Complex z = std::polar(1.0, angle(k, std::numbers::pi / static_cast<double>(m)));
    residual = std::max(residual, std::abs(eval(p, z) - value_at(z)));
  }
  // The same values by another rounding path at three points: `check`, the exponential with more
  // squarings, by full LUs (not of a Hessenberg form). Where e^(AT) or the circle's view of it is
  // ill-conditioned (poles of e^(pT) = 1e13 seen from |z| = 1, a companion form far from normal)
  // the two disagree, though each agrees with its own interpolant.
  for (std::size_t k = 0; k < 3 && k < m; ++k) {
    const Complex z = std::polar(1.0, angle(k * (m / 3), std::numbers::pi / static_cast<double>(m)));
    Eigen::MatrixXcd full = Eigen::MatrixXcd::Zero(n + 1, n + 1);
    full.topLeftCorner(n, n) = -check.phi.cast<Complex>();
    full.topLeftCorner(n, n).diagonal().array() += z;
    const Complex det_phi = Eigen::PartialPivLU<Eigen::MatrixXcd>(full.topLeftCorner(n, n)).determinant();
    full.topRightCorner(n, 1) = (check.g0 * z + check.g1).cast<Complex>();
    full.bottomLeftCorner(1, n) = -c.cast<Complex>();
    full(n, n) = check.d;
    const Complex other =
        eval(den_z, z) * (Eigen::PartialPivLU<Eigen::MatrixXcd>(full).determinant() / det_phi);
    residual = std::max(residual, std::abs(other - value_at(z)));
  }
  if (v_max == 0.0) return Poly{};
  disagreement = residual / v_max;
  if (!(residual <= k_numerator_tolerance * v_max)) return std::nullopt;
  const double noise = std::max(residual, static_cast<double>(m) * std::numeric_limits<double>::epsilon() * v_max);
  for (double& x : p) {
    if (std::abs(x) <= 8.0 * noise) x = 0.0;
  }
  return trim(p);
}

/// e^(M) for the block matrices of the holds, refused when it overflows: a pole far in the
/// right half-plane (Re p·T above about 709) has no sampled value in double.
///
/// By Taylor series with scaling and squaring, not Eigen's Padé approximant: the Padé error is
/// small beside the norm but not beside Γ's smallest entries (T^6/720 = 1.4e-21 for a sixth
/// order at 1 ms came out 1e-6 wrong); the series, summed until its terms are 1e-100 of the
/// sum, is accurate entry by entry for the small ‖M‖ of a short sample period.
Eigen::MatrixXd checked_exp(const Eigen::MatrixXd& m, const std::string& what, int extra_squarings = 0) {
  const double norm = m.cwiseAbs().colwise().sum().maxCoeff();
  int squarings = extra_squarings;
  if (norm > 0.5) squarings += std::min(2000, static_cast<int>(std::ceil(std::log2(norm / 0.5))));
  const Eigen::MatrixXd x = m * std::ldexp(1.0, -squarings);
  Eigen::MatrixXd e = Eigen::MatrixXd::Identity(m.rows(), m.cols());
  Eigen::MatrixXd term = e;
  for (int k = 1; k <= 80; ++k) {
    term = term * x / static_cast<double>(k);
    e += term;
    const double t = term.cwiseAbs().maxCoeff();
    if (t == 0.0 || t < 1e-100 * e.cwiseAbs().maxCoeff()) break;
  }
  for (int i = 0; i < squarings && e.allFinite(); ++i) e = e * e;
  if (!e.allFinite()) {
    fail("{}: e^(A*dt) overflows: a pole p with Re(p)*dt above 709 has no sampled value", what);
  }
  return e;
}

Tf tustin(const Tf& g, double dt_s, double prewarp_rad_s) {
  const double c = prewarp_rad_s > 0.0 ? prewarp_rad_s / std::tan(prewarp_rad_s * dt_s / 2.0) : 2.0 / dt_s;
  const Poly num = trim(g.num);
  const Poly den = trim(g.den);
  const int n = degree(den);
  auto map = [&](const Poly& p) {
    Poly out;
    const int m = static_cast<int>(p.size()) - 1;
    for (int i = 0; i <= m; ++i) {
      const int power = m - i;
      Poly term{p[static_cast<std::size_t>(i)] * std::pow(c, power)};
      for (int k = 0; k < power; ++k) term = mul(term, Poly{1.0, -1.0});
      for (int k = 0; k < n - power; ++k) term = mul(term, Poly{1.0, 1.0});
      out = add(out, term);
    }
    return out;
  };
  return make_z(map(num), map(den), dt_s, 0);
}

Tf matched(const Tf& g, double dt_s) {
  const Poly num = trim(g.num);
  const Poly den = trim(g.den);
  const int kz0 = zeros_at_origin(num);
  const int kp0 = zeros_at_origin(den);
  const Poly num_r = drop_origin(num, kz0);
  const Poly den_r = drop_origin(den, kp0);
  std::vector<Complex> zeros;
  std::vector<Complex> poles;
  for (const Complex& z : roots(num_r)) zeros.push_back(std::exp(z * dt_s));
  for (const Complex& p : roots(den_r)) poles.push_back(std::exp(p * dt_s));
  const int infinite = degree(den) - degree(num);
  const Poly shape_num = mul(from_roots(zeros), [&] {
    Poly p{1.0};
    for (int k = 0; k < infinite - 1; ++k) p = mul(p, Poly{1.0, 1.0});
    return p;
  }());
  const Poly shape_den = from_roots(poles);
  const double gr0 = num_r.back() / den_r.back();
  const double a1 = eval(shape_num, 1.0) / eval(shape_den, 1.0);
  const double k = gr0 * std::pow(dt_s, kp0 - kz0) / a1;
  Poly hn = scale(shape_num, k);
  Poly hd = shape_den;
  for (int i = 0; i < kz0; ++i) hn = mul(hn, Poly{1.0, -1.0});
  for (int i = 0; i < kp0; ++i) hd = mul(hd, Poly{1.0, -1.0});
  return make_z(hn, hd, dt_s, 0);
}

}  // namespace

const char* method_name(C2dMethod m) {
  switch (m) {
    case C2dMethod::zoh: return "zoh";
    case C2dMethod::foh: return "foh";
    case C2dMethod::tustin: return "tustin";
    case C2dMethod::matched: return "matched";
    case C2dMethod::impulse: return "impulse";
  }
  return "zoh";
}

C2dMethod parse_method(const std::string& text, const std::string& where) {
  for (C2dMethod m : {C2dMethod::zoh, C2dMethod::foh, C2dMethod::tustin, C2dMethod::matched, C2dMethod::impulse}) {
    if (text == method_name(m)) return m;
  }
  fail("{}: unknown discretisation method {} (zoh, foh, tustin, matched, impulse)", where, quote(text));
}

StateSpace realise(const Tf& g) {
  const Poly den = trim(g.den);
  const Poly num0 = trim(g.num);
  const int n = static_cast<int>(den.size()) - 1;
  StateSpace ss;
  Poly num(den.size(), 0.0);
  for (std::size_t i = 0; i < num0.size(); ++i) num[num.size() - num0.size() + i] = num0[i] / den[0];
  ss.d = num[0];
  ss.a = Eigen::MatrixXd::Zero(n, n);
  ss.b = Eigen::VectorXd::Zero(n);
  ss.c = Eigen::RowVectorXd::Zero(n);
  if (n == 0) return ss;
  for (int j = 0; j < n; ++j) {
    const double aj = den[static_cast<std::size_t>(j) + 1] / den[0];
    ss.a(0, j) = -aj;
    ss.c(j) = num[static_cast<std::size_t>(j) + 1] - ss.d * aj;
  }
  for (int i = 1; i < n; ++i) ss.a(i, i - 1) = 1.0;
  ss.b(0) = 1.0;
  const Eigen::VectorXd dscale = balance(ss.a);
  ss.b = ss.b.cwiseQuotient(dscale);
  ss.c = ss.c.cwiseProduct(dscale.transpose());
  return ss;
}

Poly charpoly(const Eigen::MatrixXd& a) {
  const Eigen::Index n = a.rows();
  if (n == 0) return {1.0};
  Eigen::MatrixXd h = a;
  if (n > 2) h = Eigen::HessenbergDecomposition<Eigen::MatrixXd>(a).matrixH();
  std::vector<Poly> p;
  p.push_back({1.0});
  for (Eigen::Index k = 0; k < n; ++k) {
    Poly next = mul(Poly{1.0, -h(k, k)}, p.back());
    double prod = 1.0;
    for (Eigen::Index i = k - 1; i >= 0; --i) {
      prod *= h(i + 1, i);
      next = sub(next, scale(p[static_cast<std::size_t>(i)], h(i, k) * prod));
    }
    p.push_back(next);
  }
  return p.back();
}

Poly ss_numerator(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, const Eigen::RowVectorXd& c) {
  const Eigen::MatrixXd closed = a - b * c;
  return sub(charpoly(closed), charpoly(a));
}

Tf c2d(const Tf& g, double dt_s, C2dMethod method, double prewarp_rad_s, const std::string& what) {
  if (g.discrete()) fail("{}: already discrete (z)", what);
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) fail("{}: sample period must be positive, got {}", what, dt_s);
  if (is_zero(g.num)) return make_z({}, {1.0}, dt_s, 0);
  if (!g.proper()) fail("{}: improper transfer function cannot be discretised", what);
  check_degree(g, what);
  if (method == C2dMethod::tustin) {
    const long d = whole_delay(g, dt_s, what, "tustin");
    Tf h = tustin(g, dt_s, prewarp_rad_s);
    return make_z(h.num, h.den, dt_s, d);
  }
  if (method == C2dMethod::matched) {
    const long d = whole_delay(g, dt_s, what, "matched");
    Tf h = matched(g, dt_s);
    return make_z(h.num, h.den, dt_s, d);
  }
  // The gain travels outside the realisation: 1e-300/(s+1) keeps its 1e-300 exactly.
  const Poly num0 = trim(g.num);
  double gain = 0.0;
  for (double x : num0) gain = std::max(gain, std::abs(x));
  const StateSpace ss = realise(scaled(g, 1.0 / gain));
  const Eigen::Index n = ss.a.rows();
  const Eigen::VectorXd none = Eigen::VectorXd::Zero(n);
  // Every hold samples the poles over one period: its denominator is the same.
  const Poly den_z = sampled_denominator(trim(g.den), dt_s, what);
  // The holds keep the DC gain, H(1) = G(0). Where den's coefficients cancel at z = 1 (poles
  // near 1: (1 − a)² is 1e-6 made of terms near 2) an accurate numerator over the rounded den
  // still misses it by 1e-10; a rescaling within that rounding restores it, so a step settles
  // where G does.
  auto finish = [&](const Poly& num, const Poly& den, long delay) {
    Poly h_num = scale(num, gain);
    const double g0 = num0.empty() ? 0.0 : num0.back() / trim(g.den).back();
    const double h1 = eval(h_num, 1.0) / eval(den, 1.0);
    if (method != C2dMethod::impulse && std::isfinite(g0) && std::isfinite(h1) && g0 != 0.0 &&
        std::abs(h1 / g0 - 1.0) < 1e-8) {
      h_num = scale(h_num, g0 / h1);
    }
    return make_z(h_num, den, dt_s, delay);
  };
  // Over the mapped poles first; where the root finder cannot place them (a 64-fold pole) over
  // Φ's own characteristic polynomial, if the sampled system agrees with that.
  auto discretise = [&](const Sampled& sampled, const Sampled& check, long delay) {
    double off = 0.0;
    if (auto num = numerator(sampled, check, ss.c, den_z, what, off)) return finish(*num, den_z, delay);
    const Poly den_phi = charpoly(sampled.phi);
    double off_phi = 0.0;
    if (auto num = numerator(sampled, check, ss.c, den_phi, what, off_phi)) {
      return finish(*num, den_phi, delay);
    }
    fail(
        "{}: cannot be discretised accurately: the numerator agrees with the sampled system only to {:.1g} "
        "of "
        "its size (at most {:g}); the poles or the sample period are too far apart",
        what, std::min(off, off_phi), k_numerator_tolerance);
  };
  if (method == C2dMethod::zoh) {
    long d = 0;
    double theta = 0.0;
    // A fractional delay costs one sample more: z^−(d+1).
    split_delay(g.delay_s, dt_s, k_max_degree - static_cast<int>(n) - 1, what, d, theta);
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n + 1, n + 1);
    m.topLeftCorner(n, n) = ss.a;
    m.topRightCorner(n, 1) = ss.b;
    auto sample = [&](int extra) {
      auto block_exp = [&](double t, Eigen::MatrixXd& phi, Eigen::VectorXd& psi) {
        const Eigen::MatrixXd e = checked_exp(m * t, what, extra);
        phi = e.topLeftCorner(n, n);
        psi = e.topRightCorner(n, 1);
      };
      Eigen::MatrixXd phi;
      Eigen::VectorXd gamma;
      block_exp(dt_s - theta, phi, gamma);
      if (theta == 0.0) return Sampled{phi, none, gamma, ss.d};
      Eigen::MatrixXd phi_theta;
      Eigen::VectorXd psi_theta;
      block_exp(theta, phi_theta, psi_theta);
      const Eigen::VectorXd gamma1 = phi * psi_theta;
      Eigen::MatrixXd phi_full;
      Eigen::VectorXd unused;
      block_exp(dt_s, phi_full, unused);
      // z·N0 + N1 + D·den: one bordered determinant with the column z·Γ0 + Γ1.
      return Sampled{phi_full, gamma, gamma1, ss.d};
    };
    return discretise(sample(0), sample(k_check_squarings), theta == 0.0 ? d : d + 1);
  }
  if (method == C2dMethod::foh) {
    const long d = whole_delay(g, dt_s, what, "foh");
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n + 2, n + 2);
    m.topLeftCorner(n, n) = ss.a * dt_s;
    m.block(0, n, n, 1) = ss.b * dt_s;
    m(n, n + 1) = 1.0;
    auto sample = [&](int extra) {
      const Eigen::MatrixXd e = checked_exp(m, what, extra);
      const Eigen::MatrixXd phi = e.topLeftCorner(n, n);
      const Eigen::VectorXd gamma1 = e.block(0, n, n, 1);
      const Eigen::VectorXd gamma2 = e.block(0, n + 1, n, 1);
      const Eigen::VectorXd gamma = gamma1 + (phi - Eigen::MatrixXd::Identity(n, n)) * gamma2;
      return Sampled{phi, none, gamma, ss.d + (ss.c * gamma2)(0)};
    };
    return discretise(sample(0), sample(k_check_squarings), d);
  }
  const long d = whole_delay(g, dt_s, what, "impulse");
  if (!g.strictly_proper()) fail("{}: impulse invariance needs a strictly proper transfer function", what);
  // T·z·C·adj(zI − Φ)·B: the column z·(T·B).
  auto sample = [&](int extra) {
    return Sampled{checked_exp(ss.a * dt_s, what, extra), ss.b * dt_s, none, 0.0};
  };
  return discretise(sample(0), sample(k_check_squarings), d);
}

}  // namespace mcg::linsys
