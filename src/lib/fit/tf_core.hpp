// The transfer-function fits' shared core (frequency and time domain): the scaled coefficients
// the solver moves, their s-domain form, and the Bode form with standard errors.
#pragma once

#include "fit/tf.hpp"

#include <Eigen/Core>

#include <complex>
#include <vector>

namespace mcg::fit::tf_core {

/// Coefficients in the scaled variable x = s / w0, theta = (b_0 .. b_m, a_0 .. a_{n-1}):
///   G = B(x) / A(x),  B = sum_{i<=m} b_i x^i,  A = x^n + sum_{i<n} a_i x^i  (monic).
struct Scaled {
  int m;
  int n;
  double w0;

  std::complex<double> numerator(const Eigen::VectorXd& theta, std::complex<double> x) const;
  std::complex<double> denominator(const Eigen::VectorXd& theta, std::complex<double> x) const;
  /// G(j w).
  std::complex<double> model(const Eigen::VectorXd& theta, double w) const;
};

/// s-domain coefficients (descending) from the scaled ones, normalised as RationalTf says.
RationalTf to_s_domain(const Scaled& sc, const Eigen::VectorXd& theta);

double lowest_nonzero(const std::vector<double>& c);

/// The factors of a polynomial (descending powers), sorted by corner frequency.
std::vector<Factor> factors_of(const std::vector<double>& coefficients);

/// The quantities reported with standard errors: gain, then per pole and zero factor its
/// corner and (for pairs) its damping.
Eigen::VectorXd reported(const Scaled& sc, const Eigen::VectorXd& theta);

/// Fills tf, gain, poles, zeros, the delay (the parameter after theta when fit_delay) and their
/// standard errors from fit.nls, whose first n_theta values are theta. The errors of the gain and
/// corners come from theta's covariance by the delta method, with steps relative to `largest`,
/// the magnitude of the largest coefficient.
void complete(const Scaled& sc, Eigen::Index n_theta, bool fit_delay, double largest, TfFit& fit);

}  // namespace mcg::fit::tf_core
