// Forward-mode automatic differentiation: a number with its derivatives along k_dual_dirs
// directions (the parameters a fit differentiates in one pass). The plant runs on it
// (model/plant.cpp) to carry the sensitivities of its state to the parameters along the
// simulation. Comparisons look at the value only: the plant's branches (stuck or moving,
// which event comes first) follow the value, and the derivatives those of the branch taken.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>

namespace mcg::model {

/// Directions one dual pass carries: a Jacobian of more parameters takes several passes.
inline constexpr std::size_t k_dual_dirs = 8;

/// The derivatives, as one vector: the compiler's vector extension makes every operation on
/// them a few SIMD instructions, where a loop over an array was left scalar at -O2.
using Tangent = double __attribute__((vector_size(k_dual_dirs * sizeof(double))));

struct Dual {
  double v = 0.0;
  Tangent d{};

  Dual() = default;
  Dual(double value) : v(value) {}  // NOLINT(google-explicit-constructor): a constant

  Dual& operator+=(const Dual& b) {
    v += b.v;
    d += b.d;
    return *this;
  }
  Dual& operator-=(const Dual& b) {
    v -= b.v;
    d -= b.d;
    return *this;
  }
  Dual& operator*=(const Dual& b) {
    d = d * b.v + v * b.d;
    v *= b.v;
    return *this;
  }
  Dual& operator/=(const Dual& b) {
    v /= b.v;
    d = (d - v * b.d) / b.v;
    return *this;
  }
};

inline double value_of(double x) { return x; }
inline double value_of(const Dual& x) { return x.v; }

/// f(x) with f'(x) = slope: the chain rule on every direction.
inline Dual chain(const Dual& x, double f, double slope) {
  Dual r(f);
  r.d = slope * x.d;
  return r;
}

inline Dual operator-(const Dual& a) { return chain(a, -a.v, -1.0); }
inline Dual operator+(Dual a, const Dual& b) { return a += b; }
inline Dual operator-(Dual a, const Dual& b) { return a -= b; }
inline Dual operator*(Dual a, const Dual& b) { return a *= b; }
inline Dual operator/(Dual a, const Dual& b) { return a /= b; }
inline Dual operator+(Dual a, double b) { return a.v += b, a; }
inline Dual operator+(double a, Dual b) { return b.v += a, b; }
inline Dual operator-(Dual a, double b) { return a.v -= b, a; }
inline Dual operator-(double a, const Dual& b) { return chain(b, a - b.v, -1.0); }
inline Dual operator*(const Dual& a, double b) { return chain(a, a.v * b, b); }
inline Dual operator*(double a, const Dual& b) { return chain(b, a * b.v, a); }
inline Dual operator/(const Dual& a, double b) { return chain(a, a.v / b, 1.0 / b); }
inline Dual operator/(double a, const Dual& b) { return chain(b, a / b.v, -a / (b.v * b.v)); }

// By value only (the header's first comment says why).
inline bool operator<(const Dual& a, const Dual& b) { return a.v < b.v; }
inline bool operator>(const Dual& a, const Dual& b) { return a.v > b.v; }
inline bool operator<=(const Dual& a, const Dual& b) { return a.v <= b.v; }
inline bool operator>=(const Dual& a, const Dual& b) { return a.v >= b.v; }
inline bool operator==(const Dual& a, const Dual& b) { return a.v == b.v; }
inline bool operator!=(const Dual& a, const Dual& b) { return a.v != b.v; }
inline bool operator<(const Dual& a, double b) { return a.v < b; }
inline bool operator>(const Dual& a, double b) { return a.v > b; }
inline bool operator<=(const Dual& a, double b) { return a.v <= b; }
inline bool operator>=(const Dual& a, double b) { return a.v >= b; }
inline bool operator==(const Dual& a, double b) { return a.v == b; }
inline bool operator!=(const Dual& a, double b) { return a.v != b; }
inline bool operator<(double a, const Dual& b) { return a < b.v; }
inline bool operator>(double a, const Dual& b) { return a > b.v; }
inline bool operator<=(double a, const Dual& b) { return a <= b.v; }
inline bool operator>=(double a, const Dual& b) { return a >= b.v; }

/// A root s of g(s, p) = 0 found on the values, with ds/dp = -(dg/dp) / (dg/ds) (the implicit
/// function theorem): g_at_s is g at s with its derivatives in p, dg_ds its slope in s (0: the
/// root does not move to first order).
inline double root_at(double s, double /*g_at_s*/, double /*dg_ds*/) { return s; }
inline Dual root_at(double s, const Dual& g_at_s, double dg_ds) {
  Dual r(s);
  if (dg_ds != 0.0) r.d = -g_at_s.d / dg_ds;
  return r;
}

/// x with its value replaced by v (its derivatives kept).
inline double with_value(double /*x*/, double v) { return v; }
inline Dual with_value(Dual x, double v) {
  x.v = v;
  return x;
}

/// The same derivatives (a double has none).
inline bool same_derivatives(double /*a*/, double /*b*/) { return true; }
inline bool same_derivatives(const Dual& a, const Dual& b) {
  for (std::size_t j = 0; j < k_dual_dirs; ++j) {
    if (a.d[j] != b.d[j]) return false;
  }
  return true;
}

/// Value and every derivative equal: a memo keyed on a dual may serve only the same dual.
inline bool identical(double a, double b) { return a == b; }
inline bool identical(const Dual& a, const Dual& b) { return a.v == b.v && same_derivatives(a, b); }

inline Dual abs(const Dual& x) { return x.v < 0.0 ? -x : x; }
inline Dual exp(const Dual& x) {
  const double e = std::exp(x.v);
  return chain(x, e, e);
}
inline Dual expm1(const Dual& x) { return chain(x, std::expm1(x.v), std::exp(x.v)); }
inline Dual sqrt(const Dual& x) {
  const double s = std::sqrt(x.v);
  return chain(x, s, 0.5 / s);
}
inline Dual sin(const Dual& x) { return chain(x, std::sin(x.v), std::cos(x.v)); }
inline Dual cos(const Dual& x) { return chain(x, std::cos(x.v), -std::sin(x.v)); }
inline Dual tanh(const Dual& x) {
  const double t = std::tanh(x.v);
  return chain(x, t, 1.0 - t * t);
}
/// a^b for a > 0: exp(b ln a).
inline Dual pow(const Dual& a, const Dual& b) { return exp(b * chain(a, std::log(a.v), 1.0 / a.v)); }
/// |a| with b's sign.
inline Dual copysign(const Dual& a, const Dual& b) { return (a.v < 0.0) != std::signbit(b.v) ? -a : a; }

}  // namespace mcg::model
