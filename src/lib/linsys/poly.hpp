// Real polynomials as coefficient vectors in descending powers, as MATLAB writes them.
#pragma once

#include <Eigen/Dense>

#include <complex>
#include <vector>

namespace mcg::linsys {

/// p(x) = c[0] x^n + c[1] x^(n-1) + ... + c[n]. The empty vector is the zero polynomial.
using Poly = std::vector<double>;
using Complex = std::complex<double>;

/// Removes leading zero coefficients (the zero polynomial becomes {}).
Poly trim(Poly p);
/// Degree of a trimmed polynomial; -1 for the zero polynomial.
int degree(const Poly& p);
bool is_zero(const Poly& p);
Poly add(const Poly& a, const Poly& b);
Poly sub(const Poly& a, const Poly& b);
Poly mul(const Poly& a, const Poly& b);
Poly scale(const Poly& p, double k);
/// x^n.
Poly monomial(int n);
/// p(x) by Horner's rule.
Complex eval(const Poly& p, Complex x);
double eval(const Poly& p, double x);
/// All complex roots (eigenvalues of the companion matrix, balanced, of p in a scaled variable so
/// that coefficients from 1e-308 to 1e308 keep their roots); {} for degree < 1.
std::vector<Complex> roots(const Poly& p);
/// Every root in Re s < 0 (or |z| < 1 with `unit_circle`), decided from the roots of the
/// balanced companion matrix (in s of p in a scaled variable) and a first-order bound of each
/// root's rounding error (4·n·ε per coefficient): a root within its bound of the boundary counts
/// as on it (not stable) when the bound is below 1e-6 of |root|, and throws mcg::Error
/// ("stability cannot be decided in double precision") when it is larger: then rounding alone
/// could move it across, as for (s+1)^64 + 1 or a cluster of poles near z = 1.
bool roots_stable(const Poly& p, bool unit_circle);
/// Every root in |z| < 1, by the Schur–Cohn recursion in long double: O(n²) and no roots, for
/// the many probes of a gain range; no conditioning check (roots_stable() has one).
bool schur_cohn_stable(const Poly& p);
/// Parlett–Reinsch balancing with powers of 2: A becomes D^−1·A·D, balanced; returns D.
Eigen::VectorXd balance(Eigen::MatrixXd& a);
/// The monic polynomial with these roots; conjugate pairs give real coefficients (the tiny
/// imaginary residue of rounding is dropped).
Poly from_roots(const std::vector<Complex>& r);
/// Number of roots at x = 0 (trailing zero coefficients).
int zeros_at_origin(const Poly& p);
/// p with `n` trailing zero coefficients removed (divides by x^n); n <= zeros_at_origin(p).
Poly drop_origin(const Poly& p, int n);

}  // namespace mcg::linsys
