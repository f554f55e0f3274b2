// Real polynomials as coefficient vectors in descending powers, as MATLAB writes them.
#pragma once

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
/// All complex roots (eigenvalues of the companion matrix, balanced); {} for degree < 1.
std::vector<Complex> roots(const Poly& p);
/// The monic polynomial with these roots; conjugate pairs give real coefficients (the tiny
/// imaginary residue of rounding is dropped).
Poly from_roots(const std::vector<Complex>& r);
/// Number of roots at x = 0 (trailing zero coefficients).
int zeros_at_origin(const Poly& p);
/// p with `n` trailing zero coefficients removed (divides by x^n); n <= zeros_at_origin(p).
Poly drop_origin(const Poly& p, int n);

}  // namespace mcg::linsys
