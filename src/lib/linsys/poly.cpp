// Polynomial arithmetic and roots.
#include "linsys/poly.hpp"

#include <Eigen/Dense>

#include "common/demand.hpp"
#include "common/error.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace mcg::linsys {

Poly trim(Poly p) {
  const auto first = std::find_if(p.begin(), p.end(), [](double c) { return c != 0.0; });
  p.erase(p.begin(), first);
  return p;
}

int degree(const Poly& p) {
  const Poly t = trim(p);
  return static_cast<int>(t.size()) - 1;
}

bool is_zero(const Poly& p) { return trim(p).empty(); }

Poly add(const Poly& a, const Poly& b) {
  Poly r(std::max(a.size(), b.size()), 0.0);
  const std::size_t oa = r.size() - a.size();
  const std::size_t ob = r.size() - b.size();
  for (std::size_t i = 0; i < a.size(); ++i) r[oa + i] += a[i];
  for (std::size_t i = 0; i < b.size(); ++i) r[ob + i] += b[i];
  return trim(r);
}

Poly sub(const Poly& a, const Poly& b) { return add(a, scale(b, -1.0)); }

Poly mul(const Poly& a, const Poly& b) {
  if (a.empty() || b.empty()) return {};
  Poly r(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
  }
  return trim(r);
}

Poly scale(const Poly& p, double k) {
  Poly r = p;
  for (double& c : r) c *= k;
  return trim(r);
}

Poly monomial(int n) {
  MCG_DEMAND(n >= 0);
  Poly r(static_cast<std::size_t>(n) + 1, 0.0);
  r[0] = 1.0;
  return r;
}

Complex eval(const Poly& p, Complex x) {
  Complex acc = 0.0;
  for (double c : p) acc = acc * x + c;
  return acc;
}

double eval(const Poly& p, double x) {
  double acc = 0.0;
  for (double c : p) acc = acc * x + c;
  return acc;
}

/// Parlett–Reinsch balancing with powers of 2: returns D with D^−1·A·D balanced (A updated).
Eigen::VectorXd balance(Eigen::MatrixXd& a) {
  const Eigen::Index n = a.rows();
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  bool converged = false;
  for (int sweep = 0; sweep < 100 && !converged; ++sweep) {
    converged = true;
    for (Eigen::Index i = 0; i < n; ++i) {
      double c = 0.0;
      double r = 0.0;
      for (Eigen::Index j = 0; j < n; ++j) {
        if (j == i) continue;
        c += std::abs(a(j, i));
        r += std::abs(a(i, j));
      }
      if (c == 0.0 || r == 0.0) continue;
      const double s = c + r;
      double f = 1.0;
      double g = r / 2.0;
      while (c < g) {
        f *= 2.0;
        c *= 4.0;
      }
      g = r * 2.0;
      while (c >= g) {
        f /= 2.0;
        c /= 4.0;
      }
      if ((c + r) / f < 0.95 * s) {
        converged = false;
        d(i) *= f;
        a.row(i) /= f;
        a.col(i) *= f;
      }
    }
  }
  return d;
}

namespace {

/// p's coefficients in x = s/σ, σ = 2^k near (|c_n|/|c_0|)^(1/n) (a power of 2: the scaling
/// rounds nothing), scaled to a largest of 1: formed in logarithms, so that 1e308·s + 1e-308
/// becomes x + 1 instead of an underflow to x + 0.
Poly scaled_variable(const Poly& q, int& k) {
  const int m = static_cast<int>(q.size()) - 1;
  k = static_cast<int>(std::lround((std::log2(std::abs(q.back())) - std::log2(std::abs(q.front()))) / m));
  // c_i s^(m−i) = c_i 2^(k(m−i)) x^(m−i), by exponents alone: exact but for what underflows
  // beside the largest.
  std::vector<int> exponents(q.size());
  std::vector<double> mantissas(q.size());
  int top = std::numeric_limits<int>::min();
  for (std::size_t i = 0; i < q.size(); ++i) {
    int e = 0;
    mantissas[i] = std::frexp(q[i], &e);
    exponents[i] = e + (m - static_cast<int>(i)) * k;
    if (q[i] != 0.0) top = std::max(top, exponents[i]);
  }
  Poly r(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) r[i] = q[i] == 0.0 ? 0.0 : std::ldexp(mantissas[i], exponents[i] - top);
  return r;
}

/// Roots of a polynomial with no root at 0, as eigenvalues of its balanced companion matrix.
std::vector<Complex> companion_roots(const Poly& q) {
  const int m = static_cast<int>(q.size()) - 1;
  std::vector<Complex> out;
  if (m == 1) {
    out.emplace_back(-q[1] / q[0], 0.0);
    return out;
  }
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(m, m);
  for (int j = 0; j < m; ++j) companion(0, j) = -q[static_cast<std::size_t>(j) + 1] / q[0];
  for (int i = 1; i < m; ++i) companion(i, i - 1) = 1.0;
  balance(companion);
  Eigen::EigenSolver<Eigen::MatrixXd> solver(companion, false);
  const auto& ev = solver.eigenvalues();
  for (int i = 0; i < m; ++i) out.push_back(ev(i));
  return out;
}

void sort_roots(std::vector<Complex>& r) {
  std::sort(r.begin(), r.end(), [](Complex a, Complex b) {
    return a.real() != b.real() ? a.real() < b.real() : a.imag() < b.imag();
  });
}

}  // namespace

std::vector<Complex> roots(const Poly& p0) {
  const Poly p = trim(p0);
  const int n = static_cast<int>(p.size()) - 1;
  if (n < 1) return {};
  const int nz = zeros_at_origin(p);
  std::vector<Complex> out(static_cast<std::size_t>(nz), Complex(0.0, 0.0));
  const Poly q = drop_origin(p, nz);
  if (q.size() > 1) {
    int k = 0;
    const Poly x = scaled_variable(q, k);
    for (const Complex& r : companion_roots(x)) out.emplace_back(std::ldexp(r.real(), k), std::ldexp(r.imag(), k));
  }
  sort_roots(out);
  return out;
}

bool roots_stable(const Poly& p0, bool unit_circle) {
  const Poly p = trim(p0);
  if (p.size() <= 1) return true;
  if (zeros_at_origin(p) > 0 && !unit_circle) return false;
  // In s a scaled variable keeps the sign of Re; in z the circle fixes the scale.
  int scale_k = 0;
  const Poly q = unit_circle ? scale(p, 1.0 / std::abs(p.front())) : scaled_variable(p, scale_k);
  const int m = static_cast<int>(q.size()) - 1;
  Poly abs_q = q;
  for (double& c : abs_q) c = std::abs(c);
  const int nz = unit_circle ? zeros_at_origin(q) : 0;
  if (m - nz < 1) return true;
  bool unstable = false;
  bool undecided = false;
  Complex worst;
  double worst_bound = 0.0;
  for (Complex x : companion_roots(drop_origin(q, nz))) {
    // Radius of the root's neighbourhood for a backward error E = 4·n·ε in each coefficient:
    // min over k of (k!·E/|q^(k)(x)|)^(1/k), Taylor's estimate, which a cluster of k roots
    // needs (a double root's first derivative is 0, its neighbourhood sqrt(E) wide).
    const double err = 4.0 * m * std::numeric_limits<double>::epsilon() * eval(abs_q, std::abs(x));
    double bound = std::numeric_limits<double>::infinity();
    Poly derivative = q;
    double factorial = 1.0;
    for (int k = 1; k <= std::min(m, 8); ++k) {
      Poly next;
      const int deg = static_cast<int>(derivative.size()) - 1;
      for (int i = 0; i < deg; ++i) next.push_back(derivative[static_cast<std::size_t>(i)] * (deg - i));
      derivative = next;
      factorial *= k;
      const double slope = std::abs(eval(derivative, x));
      if (slope > 0.0) bound = std::min(bound, std::pow(factorial * err / slope, 1.0 / k));
    }
    // Distance inside the boundary: −Re s, or 1 − |z|.
    const double inside = unit_circle ? 1.0 - std::abs(x) : -x.real();
    if (inside < -bound) {
      unstable = true;
    } else if (!(inside > bound)) {
      // On the boundary as far as double can tell: marginal (not stable) when the bound is
      // tight, undecidable when rounding alone could move the root across.
      if (bound <= 1e-6 * std::max(std::abs(x), 1.0)) {
        unstable = true;
      } else if (!undecided || bound > worst_bound) {
        undecided = true;
        worst = x;
        worst_bound = bound;
      }
    }
  }
  if (unstable) return false;
  if (undecided) {
    const double sigma = std::ldexp(1.0, scale_k);
    fail("closed-loop stability cannot be decided in double precision: the pole near {} = {:.6g}{:+.6g}j of a "
         "degree-{} characteristic polynomial may be off by {:.2g}, across the {}",
         unit_circle ? "z" : "s", worst.real() * sigma, worst.imag() * sigma, m, worst_bound * sigma,
         unit_circle ? "unit circle" : "imaginary axis");
  }
  return true;
}

bool schur_cohn_stable(const Poly& p0) {
  std::vector<long double> a;
  for (double c : trim(p0)) a.push_back(c);
  // Schur–Cohn: all roots inside |z| < 1 iff every reflection coefficient r = a_n/a_0 of the
  // recursion a_i <- a_i − r·a_(n−i) (degree n to n−1) has |r| < 1.
  while (a.size() > 1) {
    const long double r = a.back() / a.front();
    if (!(std::abs(r) < 1.0L)) return false;
    const std::size_t n = a.size() - 1;
    std::vector<long double> b(n);
    for (std::size_t i = 0; i < n; ++i) b[i] = a[i] - r * a[n - i];
    a = std::move(b);
  }
  return true;
}

Poly from_roots(const std::vector<Complex>& r) {
  std::vector<Complex> c{Complex(1.0, 0.0)};
  for (const Complex& root : r) {
    std::vector<Complex> next(c.size() + 1, Complex(0.0, 0.0));
    for (std::size_t i = 0; i < c.size(); ++i) {
      next[i] += c[i];
      next[i + 1] -= c[i] * root;
    }
    c = std::move(next);
  }
  Poly out(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) out[i] = c[i].real();
  return out;
}

int zeros_at_origin(const Poly& p0) {
  const Poly p = trim(p0);
  int n = 0;
  for (auto it = p.rbegin(); it != p.rend() && *it == 0.0; ++it) ++n;
  return n;
}

Poly drop_origin(const Poly& p, int n) {
  MCG_DEMAND(n >= 0 && static_cast<std::size_t>(n) <= p.size());
  Poly r = trim(p);
  r.resize(r.size() - static_cast<std::size_t>(n));
  return r;
}

}  // namespace mcg::linsys
