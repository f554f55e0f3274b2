// Polynomial arithmetic and roots.
#include "linsys/poly.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include "common/demand.hpp"
#include <cstddef>

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

std::vector<Complex> roots(const Poly& p0) {
  const Poly p = trim(p0);
  const int n = static_cast<int>(p.size()) - 1;
  if (n < 1) return {};
  const int nz = zeros_at_origin(p);
  std::vector<Complex> out(static_cast<std::size_t>(nz), Complex(0.0, 0.0));
  const Poly q = drop_origin(p, nz);
  const int m = n - nz;
  if (m == 1) {
    out.emplace_back(-q[1] / q[0], 0.0);
  } else if (m > 1) {
    Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(m, m);
    for (int j = 0; j < m; ++j) companion(0, j) = -q[static_cast<std::size_t>(j) + 1] / q[0];
    for (int i = 1; i < m; ++i) companion(i, i - 1) = 1.0;
    Eigen::EigenSolver<Eigen::MatrixXd> solver(companion, false);
    const auto& ev = solver.eigenvalues();
    for (int i = 0; i < m; ++i) out.push_back(ev(i));
  }
  std::sort(out.begin(), out.end(), [](Complex a, Complex b) {
    return a.real() != b.real() ? a.real() < b.real() : a.imag() < b.imag();
  });
  return out;
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
