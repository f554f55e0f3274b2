// Nonlinear least squares for every mcg fit: Eigen's Levenberg-Marquardt (MINPACK's lmder)
// with finite-difference Jacobians, parameter scaling, log-parameterised positive
// parameters, and the usual statistics (standard errors, correlations) at the optimum.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace mcg::fit {

/// How the solver moves a parameter. The solver works on u; the residual function sees p.
///   linear: p = p0 + scale * u          (any sign)
///   log:    p = p0 * exp(u)             (keeps p > 0 and makes steps relative)
enum class Transform { linear, log };

struct ParameterSpec {
  std::string name;
  double initial = 0.0;
  Transform transform = Transform::linear;
  /// Typical magnitude of a linear parameter, the solver's unit step; 0 means |initial|
  /// (or 1 if the initial value is 0). Ignored for log parameters.
  double scale = 0.0;
};

struct NlsOptions {
  /// Stop after this many residual evaluations (Jacobian columns included). A forward-difference
  /// Jacobian is charged n + 1, its base point included, though that point (where the solver
  /// stands) is looked up rather than evaluated again: no point is evaluated twice.
  int max_evaluations = 4000;
  /// Relative change of the scaled parameters below which the solver stops (MINPACK xtol).
  double xtol = 1e-8;
  /// Relative reduction of the sum of squares below which the solver stops (MINPACK ftol).
  double ftol = 1e-10;
  /// Finite-difference step in solver coordinates u (a relative step for log parameters).
  double fd_step = 1e-6;
  /// Central differences (2 evaluations per column) instead of forward (1 per column).
  bool central_differences = false;
  /// Threads evaluating Jacobian columns at once (1 = in the caller's thread; 0 = the current
  /// parallel::Pool, or every core outside one). The residual function must then be safe to
  /// call concurrently; it sees the same value in FitProblem's simulations of its runs.
  unsigned threads = 1;
  /// Between finite-difference Jacobians, update the last one by Broyden's rank-one formula
  ///   J+ = J + (dr - J du) du^T / |du|^2   (du, dr: the accepted step and its change of r)
  /// instead of simulating a column per parameter. An updated Jacobian gets one trial step: a
  /// rejected trial, or a convergence test met on it, has the next Jacobian by finite
  /// differences, so the solver stops only on a finite-difference Jacobian, and the statistics
  /// at the optimum always use one.
  bool broyden = false;
  /// The Jacobian by sensitivities (model/sensitivity.hpp) instead of finite differences: fills
  /// r (size m) and jac (m x n, dr/dp in the specs' physical units) at p and returns true, or
  /// returns false where it cannot (the solver then takes finite differences there). It is
  /// charged the evaluations of a finite-difference Jacobian, which it costs about as much.
  std::function<bool(const Eigen::VectorXd& p, Eigen::VectorXd& r, Eigen::MatrixXd& jac)> sensitivities;
  /// Check at the optimum whether the residual is smooth in each parameter (NlsResult::rough),
  /// at the cost of one more Jacobian.
  bool check_smoothness = true;
  /// Asked before every iteration and every evaluation inside one: true stops the solver there
  /// (a time budget), with the result so far (the start, when it is true at once), not
  /// converged and without statistics (NlsResult::stopped). Empty: never stops.
  std::function<bool()> stop;
};

/// The optimum and its statistics. With J the Jacobian of the residuals r with respect to
/// p at the optimum, m residuals and n parameters:
///   sigma^2 = |r|^2 / (m - n),  cov(p) = sigma^2 (J^T J)^-1,
///   std_errors_i = sqrt(cov_ii),  correlation_ij = cov_ij / (std_i std_j).
/// A direction the data does not determine (J^T J singular) gives infinite standard
/// errors and NaN correlations for the parameters it involves.
struct NlsResult {
  std::vector<std::string> names;
  Eigen::VectorXd values;
  Eigen::VectorXd std_errors;
  Eigen::MatrixXd correlation;
  Eigen::VectorXd residuals;  ///< at the optimum
  /// dr/dp at the optimum (m x n), the statistics' Jacobian; empty when the fit was stopped.
  Eigen::MatrixXd jacobian;
  double cost = 0.0;          ///< |r|^2
  double sigma = 0.0;         ///< sqrt(|r|^2 / (m - n)), NaN if m == n
  /// Per parameter: the residual is not smooth at the optimum (the Jacobian column at the
  /// finite-difference step and at 100 times it differ by more than half their size), so a
  /// standard error from the local Jacobian means nothing.
  std::vector<bool> rough;
  bool converged = false;
  /// The caller's stop ended the fit (a time budget): the values are the last accepted step's,
  /// and no Jacobian is spent on statistics (standard errors and correlations NaN, nothing rough).
  bool stopped = false;
  std::string reason;  ///< why the solver stopped, in words
  int iterations = 0;
  int evaluations = 0;
  /// Residual evaluations made, Jacobian columns and the statistics' Jacobian included (each
  /// point once: a point evaluated before is looked up).
  int simulations = 0;
  /// Jacobians by finite differences, by sensitivities (NlsOptions::sensitivities) and by
  /// Broyden updates (NlsOptions::broyden).
  int fd_jacobians = 0;
  int sensitivity_jacobians = 0;
  int broyden_jacobians = 0;
};

/// Fills r (size m, preallocated) with the residuals at parameter values p (physical
/// units, in the order of the specs). Non-finite residuals are treated as a very poor fit,
/// so the solver backs off from parameter values where the model breaks down.
using ResidualFunction = std::function<void(const Eigen::VectorXd& p, Eigen::VectorXd& r)>;

/// Minimises |r(p)|^2 over p starting from the specs' initial values.
/// Throws mcg::Error if there are fewer residuals than parameters or a log parameter does
/// not start positive. A run that stops for any reason other than a convergence test
/// (evaluation budget spent, numerical trouble) returns converged = false and says why.
NlsResult least_squares(const std::vector<ParameterSpec>& specs, std::size_t residual_count,
                        const ResidualFunction& residuals, const NlsOptions& options = {});

/// Standard errors and correlations from a Jacobian J (m x n) and residuals r (size m),
/// as documented at NlsResult. Shared by fits that solve their own way.
void covariance_statistics(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& residuals,
                           Eigen::VectorXd& std_errors, Eigen::MatrixXd& correlation, double& sigma);

}  // namespace mcg::fit
