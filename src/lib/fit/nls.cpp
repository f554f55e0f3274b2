// Levenberg-Marquardt via Eigen's unsupported module (a port of MINPACK's lmder).
#include "fit/nls.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <unsupported/Eigen/LevenbergMarquardt>

#include "common/error.hpp"
#include "common/parallel.hpp"

namespace mcg::fit {

namespace {

/// Residual value standing in for a non-finite one: large enough that any step into a
/// region where the model breaks down is rejected by the trust-region test.
constexpr double k_penalty = 1e10;

struct Coordinates {
  std::vector<ParameterSpec> specs;
  Eigen::VectorXd scale;

  explicit Coordinates(const std::vector<ParameterSpec>& s) : specs(s), scale(static_cast<Eigen::Index>(s.size())) {
    for (std::size_t i = 0; i < specs.size(); ++i) {
      const auto& spec = specs[i];
      double sc = spec.scale > 0 ? spec.scale : std::abs(spec.initial);
      if (sc == 0.0) sc = 1.0;
      scale[static_cast<Eigen::Index>(i)] = sc;
    }
  }

  Eigen::VectorXd to_physical(const Eigen::VectorXd& u) const {
    Eigen::VectorXd p(u.size());
    for (Eigen::Index i = 0; i < u.size(); ++i) {
      const auto& spec = specs[static_cast<std::size_t>(i)];
      p[i] = spec.transform == Transform::log ? spec.initial * std::exp(u[i]) : spec.initial + scale[i] * u[i];
    }
    return p;
  }

  /// dp/du at p: the chain-rule factor from solver to physical coordinates.
  Eigen::VectorXd derivative(const Eigen::VectorXd& p) const {
    Eigen::VectorXd d(p.size());
    for (Eigen::Index i = 0; i < p.size(); ++i) {
      d[i] = specs[static_cast<std::size_t>(i)].transform == Transform::log ? p[i] : scale[i];
    }
    return d;
  }
};

void sanitise(Eigen::VectorXd& r) {
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    if (!std::isfinite(r[i])) r[i] = k_penalty;
  }
}

/// Thrown out of an evaluation inside an iteration once the caller's stop says so: the
/// iteration is abandoned, its parameters are those of the last accepted step.
struct Interrupted {};

/// Thrown out of a second trial step on a Broyden-updated Jacobian (NlsOptions::broyden): the
/// iteration is abandoned at the last accepted point and redone on finite differences.
struct Refresh {};

struct Functor : Eigen::DenseFunctor<double> {
  const Coordinates& coords;
  const ResidualFunction& residuals;
  const NlsOptions& options;
  bool interruptible = false;  ///< evaluations ask options.stop first (inside the iterations)

  Functor(const Coordinates& c, const ResidualFunction& r, const NlsOptions& o, int n, int m)
      : Eigen::DenseFunctor<double>(n, m), coords(c), residuals(r), options(o) {}

  void evaluate(const Eigen::VectorXd& u, Eigen::VectorXd& r) const {
    if (interruptible && options.stop && options.stop()) throw Interrupted{};
    m_simulations.fetch_add(1, std::memory_order_relaxed);
    r.resize(values());
    residuals(coords.to_physical(u), r);
    sanitise(r);
  }

  /// The residuals at u when u is the best point the solver has evaluated (the point it
  /// differentiates next, and the optimum it returns), looked up instead of simulated again.
  bool recall(const Eigen::VectorXd& u, Eigen::VectorXd& r) const {
    if (m_best_u.size() != u.size() || !(m_best_u.array() == u.array()).all()) return false;
    r = m_best_r;
    return true;
  }

  /// An evaluation by the solver's own thread (never a Jacobian column's): kept when it is the
  /// best so far. The solver accepts a step only when it lowers the cost, so the best point is
  /// where it stands.
  void remember(const Eigen::VectorXd& u, const Eigen::VectorXd& r) const {
    const double cost = r.squaredNorm();
    if (m_best_u.size() == 0 || cost < m_best_cost) {
      m_best_u = u;
      m_best_r = r;
      m_best_cost = cost;
    }
  }

  /// The residuals at u, looked up when u is the best point so far.
  void at(const Eigen::VectorXd& u, Eigen::VectorXd& r) const {
    if (recall(u, r)) return;
    evaluate(u, r);
    remember(u, r);
  }

  /// The solver's own evaluations: its start, and the trial steps of an iteration.
  int operator()(const InputType& u, ValueType& r) const {
    if (m_trials > 0 && !m_jac_fd) throw Refresh{};
    if (m_jac_u.size() > 0) ++m_trials;
    at(u, r);
    return 0;
  }

  void column(const Eigen::VectorXd& u, const Eigen::VectorXd& r0, Eigen::Index j, JacobianType& jac) const {
    const double h = options.fd_step * std::max(1.0, std::abs(u[j]));
    Eigen::VectorXd up = u;
    Eigen::VectorXd rp;
    up[j] = u[j] + h;
    evaluate(up, rp);
    if (options.central_differences) {
      Eigen::VectorXd rm;
      up[j] = u[j] - h;
      evaluate(up, rm);
      jac.col(j) = (rp - rm) / (2.0 * h);
    } else {
      jac.col(j) = (rp - r0) / h;
    }
  }

  /// The Jacobian in solver coordinates about u, whose residuals are r0 (unused by central
  /// differences): by the sensitivities where they are given and can, else by finite differences.
  void jacobian(const Eigen::VectorXd& u, const Eigen::VectorXd& r0, JacobianType& jac) const {
    if (options.sensitivities) {
      if (interruptible && options.stop && options.stop()) throw Interrupted{};
      const Eigen::VectorXd p = coords.to_physical(u);
      Eigen::VectorXd r;
      Eigen::MatrixXd dr_dp;
      m_simulations.fetch_add(1, std::memory_order_relaxed);
      if (options.sensitivities(p, r, dr_dp) && dr_dp.allFinite() && dr_dp.rows() == values() &&
          dr_dp.cols() == inputs()) {
        jac = dr_dp * coords.derivative(p).asDiagonal();
        ++m_sensitivity_jacobians;
        return;
      }
    }
    jac.resize(values(), inputs());
    const auto n = static_cast<std::size_t>(inputs());
    parallel::for_each(n, options.threads,
                       [&](std::size_t j) { column(u, r0, static_cast<Eigen::Index>(j), jac); });
  }

  /// The solver's Jacobian; returns the evaluations it is charged. A forward-difference
  /// Jacobian is charged its base point too, though that is looked up (the solver evaluated it
  /// last): the budget then stops a fit where it always did, and the lookup only saves time.
  int df(const InputType& u, JacobianType& jac) const {
    Eigen::VectorXd r0;
    if (!options.central_differences || options.broyden) at(u, r0);
    m_trials = 0;
    if (options.broyden && !m_force_fd && m_jac_u.size() == u.size()) {
      const Eigen::VectorXd du = u - m_jac_u;
      const double du2 = du.squaredNorm();
      if (du2 > 0.0) {
        m_jac += (r0 - m_jac_r - m_jac * du) * (du.transpose() / du2);
        jac = m_jac;
        m_jac_u = u;
        m_jac_r = r0;
        m_jac_fd = false;
        ++m_broyden_jacobians;
        return 0;  // no evaluation
      }
    }
    const int by_sensitivities = m_sensitivity_jacobians;
    jacobian(u, r0, jac);
    m_jac = jac;
    m_jac_u = u;
    m_jac_r = r0;
    m_jac_fd = true;
    m_force_fd = false;
    if (m_sensitivity_jacobians == by_sensitivities) ++m_fd_jacobians;
    const int per_column = options.central_differences ? 2 : 1;
    return per_column * inputs() + (options.central_differences ? 0 : 1);
  }

  /// The Jacobian at u for the statistics: the solver's last one when it is a Jacobian at u by
  /// differences or sensitivities, not an update (the solver stopped where it differentiated),
  /// else a new one.
  void final_jacobian(const Eigen::VectorXd& u, const Eigen::VectorXd& r, JacobianType& jac) const {
    if (m_jac_fd && m_jac_u.size() == u.size() && (m_jac_u.array() == u.array()).all()) {
      jac = m_jac;
      return;
    }
    jacobian(u, r, jac);
  }

  /// The last Jacobian the solver used was a Broyden update.
  bool on_broyden() const { return m_jac_u.size() > 0 && !m_jac_fd; }
  /// The next Jacobian by differences or sensitivities, not an update.
  void refresh() const { m_force_fd = true; }

  int simulations() const { return m_simulations.load(); }
  int fd_jacobians() const { return m_fd_jacobians; }
  int broyden_jacobians() const { return m_broyden_jacobians; }
  int sensitivity_jacobians() const { return m_sensitivity_jacobians; }

 private:
  mutable Eigen::VectorXd m_best_u;
  mutable Eigen::VectorXd m_best_r;
  mutable double m_best_cost = 0.0;
  mutable std::atomic<int> m_simulations{0};
  /// The solver's last Jacobian (before its QR factorisation), where and how it was made.
  mutable Eigen::MatrixXd m_jac;
  mutable Eigen::VectorXd m_jac_u;
  mutable Eigen::VectorXd m_jac_r;
  mutable bool m_jac_fd = false;  ///< the last Jacobian is by differences or sensitivities, not an update
  mutable bool m_force_fd = true;
  mutable int m_trials = 0;  ///< trial steps on the current Jacobian
  mutable int m_fd_jacobians = 0;
  mutable int m_broyden_jacobians = 0;
  mutable int m_sensitivity_jacobians = 0;
};

/// A status of a convergence test (the solver stands at its optimum).
bool converged_status(Eigen::LevenbergMarquardtSpace::Status status) {
  using namespace Eigen::LevenbergMarquardtSpace;
  switch (status) {
    case RelativeReductionTooSmall:
    case RelativeErrorTooSmall:
    case RelativeErrorAndReductionTooSmall:
    case CosinusTooSmall:
    case FtolTooSmall:
    case XtolTooSmall:
    case GtolTooSmall:
      return true;
    default:
      return false;
  }
}

std::string describe(Eigen::LevenbergMarquardtSpace::Status status, bool& converged) {
  using namespace Eigen::LevenbergMarquardtSpace;
  converged = true;
  switch (status) {
    case RelativeReductionTooSmall:
      return "relative reduction of the sum of squares below ftol";
    case RelativeErrorTooSmall:
      return "relative parameter change below xtol";
    case RelativeErrorAndReductionTooSmall:
      return "relative reduction below ftol and parameter change below xtol";
    case CosinusTooSmall:
      return "residuals orthogonal to the Jacobian (gradient zero)";
    case FtolTooSmall:
      return "no further reduction of the sum of squares possible (machine precision)";
    case XtolTooSmall:
      return "no further improvement of the parameters possible (machine precision)";
    case GtolTooSmall:
      return "gradient orthogonal to the residuals within machine precision";
    case TooManyFunctionEvaluation:
      converged = false;
      return "evaluation budget spent before convergence";
    default:
      converged = false;
      return "numerical trouble in the solver (non-finite Jacobian or improper input)";
  }
}

}  // namespace

void covariance_statistics(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& residuals,
                           Eigen::VectorXd& std_errors, Eigen::MatrixXd& correlation, double& sigma) {
  const Eigen::Index m = jacobian.rows();
  const Eigen::Index n = jacobian.cols();
  sigma = m > n ? std::sqrt(residuals.squaredNorm() / static_cast<double>(m - n))
                : std::numeric_limits<double>::quiet_NaN();
  // Column equilibration first, so that parameters of very different magnitudes do not
  // make J^T J look singular.
  Eigen::VectorXd norms = jacobian.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < n; ++j) {
    if (norms[j] == 0.0) norms[j] = 1.0;
  }
  const Eigen::MatrixXd scaled = jacobian * norms.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeThinV);
  const Eigen::VectorXd& s = svd.singularValues();
  const double tol = s.size() > 0 ? s[0] * 1e-10 : 0.0;
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(n, n);
  std::vector<bool> undetermined(static_cast<std::size_t>(n), false);
  for (Eigen::Index k = 0; k < s.size(); ++k) {
    const Eigen::VectorXd v = svd.matrixV().col(k);
    if (s[k] > tol) {
      cov += v * v.transpose() / (s[k] * s[k]);
    } else {
      for (Eigen::Index j = 0; j < n; ++j) {
        if (std::abs(v[j]) > 1e-6) undetermined[static_cast<std::size_t>(j)] = true;
      }
    }
  }
  cov = norms.cwiseInverse().asDiagonal() * cov * norms.cwiseInverse().asDiagonal();
  cov = 0.5 * (cov + cov.transpose()).eval();
  const double s2 = std::isfinite(sigma) ? sigma * sigma : 0.0;
  std_errors.resize(n);
  correlation.resize(n, n);
  constexpr double inf = std::numeric_limits<double>::infinity();
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  for (Eigen::Index i = 0; i < n; ++i) {
    std_errors[i] = undetermined[static_cast<std::size_t>(i)] ? inf : std::sqrt(s2 * cov(i, i));
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) {
      const bool bad = undetermined[static_cast<std::size_t>(i)] || undetermined[static_cast<std::size_t>(j)];
      const double d = std::sqrt(cov(i, i) * cov(j, j));
      correlation(i, j) = i == j ? 1.0 : (bad || d == 0.0 ? nan : cov(i, j) / d);
    }
  }
}

NlsResult least_squares(const std::vector<ParameterSpec>& specs, std::size_t residual_count,
                        const ResidualFunction& residuals, const NlsOptions& options) {
  const auto n = static_cast<int>(specs.size());
  const auto m = static_cast<int>(residual_count);
  if (n == 0) fail("nothing to fit: no free parameters");
  if (m < n) fail("too little data: {} residuals for {} free parameters", m, n);
  for (const auto& spec : specs) {
    if (spec.transform == Transform::log && !(spec.initial > 0.0)) {
      fail("parameter {} must start positive (initial value {})", quote(spec.name), spec.initial);
    }
    if (!std::isfinite(spec.initial)) fail("parameter {} has a non-finite initial value", quote(spec.name));
  }
  const Coordinates coords(specs);
  Functor functor(coords, residuals, options, n, m);
  {
    const Eigen::VectorXd u0 = Eigen::VectorXd::Zero(n);
    Eigen::VectorXd r(m);
    residuals(coords.to_physical(u0), r);
    if (!r.allFinite()) fail("the model gives non-finite residuals at the initial parameter values");
    functor.remember(u0, r);  // the solver starts here
  }

  Eigen::LevenbergMarquardt<Functor> lm(functor);
  lm.setXtol(options.xtol);
  lm.setFtol(options.ftol);
  lm.setGtol(0.0);
  lm.setMaxfev(options.max_evaluations);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  // Eigen's minimize() loop, with the caller's stop asked before every iteration (a fit begun
  // after its budget ran out returns its start at once) and before every evaluation inside
  // one: a budget is kept within one simulation of the runs, not one iteration (a Jacobian and
  // its trial steps). Eigen moves u only once a trial step is accepted, so an interrupted
  // iteration leaves u at the last accepted point.
  auto status = lm.minimizeInit(u);
  bool stopped = false;
  if (status != Eigen::LevenbergMarquardtSpace::ImproperInputParameters) {
    functor.interruptible = true;
    try {
      do {
        stopped = options.stop && options.stop();
        if (stopped) break;
        try {
          status = lm.minimizeOneStep(u);
        } catch (const Refresh&) {
          status = Eigen::LevenbergMarquardtSpace::Running;
          functor.refresh();
          continue;
        }
        // A convergence test met on an updated Jacobian may be the update's error: go on from
        // there on finite differences.
        if (converged_status(status) && functor.on_broyden()) {
          status = Eigen::LevenbergMarquardtSpace::Running;
          functor.refresh();
        }
      } while (status == Eigen::LevenbergMarquardtSpace::Running);
    } catch (const Interrupted&) {
      stopped = true;
    }
    functor.interruptible = false;
  }

  NlsResult result;
  for (const auto& spec : specs) result.names.push_back(spec.name);
  result.stopped = stopped;
  result.reason = stopped ? "stopped early (time budget spent)" : describe(status, result.converged);
  result.iterations = static_cast<int>(lm.iterations());
  result.evaluations = static_cast<int>(lm.nfev());
  result.values = coords.to_physical(u);
  functor.at(u, result.residuals);
  result.cost = result.residuals.squaredNorm();
  if (result.cost >= k_penalty) {
    result.converged = false;
    result.reason = "the model breaks down (non-finite output) at the solution";
  }

  // A stopped fit spends no Jacobian on statistics: its budget is spent, and the caller reports
  // the values it reached as such.
  if (stopped) {
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    result.sigma = m > n ? std::sqrt(result.cost / static_cast<double>(m - n)) : nan;
    result.std_errors = Eigen::VectorXd::Constant(n, nan);
    result.correlation = Eigen::MatrixXd::Constant(n, n, nan);
    result.correlation.diagonal().setOnes();
    result.rough.assign(specs.size(), false);
    return result;
  }
  Eigen::MatrixXd jac_u;
  functor.final_jacobian(u, result.residuals, jac_u);
  // A discontinuity (a friction level at a breakaway) makes a small finite-difference step
  // see a jump: the column then shrinks in proportion to a larger step.
  result.rough.assign(specs.size(), false);
  if (options.check_smoothness) {
    NlsOptions wide = options;
    wide.fd_step = 100.0 * options.fd_step;
    wide.central_differences = false;
    const Functor coarse(coords, residuals, wide, n, m);
    Eigen::MatrixXd jac_wide;
    coarse.jacobian(u, result.residuals, jac_wide);
    result.simulations += coarse.simulations();
    for (Eigen::Index j = 0; j < n; ++j) {
      const double a = jac_u.col(j).norm();
      const double b = jac_wide.col(j).norm();
      const double d = (jac_u.col(j) - jac_wide.col(j)).norm();
      result.rough[static_cast<std::size_t>(j)] = std::isfinite(a) && std::isfinite(b) && d > 0.5 * std::max(a, b);
    }
  }
  result.simulations += 1 + functor.simulations();  // the start, evaluated outside the solver
  result.fd_jacobians = functor.fd_jacobians();
  result.broyden_jacobians = functor.broyden_jacobians();
  result.sensitivity_jacobians = functor.sensitivity_jacobians();
  const Eigen::VectorXd dp_du = coords.derivative(result.values);
  const Eigen::MatrixXd jac_p = jac_u * dp_du.cwiseInverse().asDiagonal();
  result.jacobian = jac_p;
  // A log parameter driven to its zero bound (many orders of magnitude below its start) has a
  // Jacobian column of rounding noise divided by almost nothing: it is held where it is for the
  // statistics (infinite error: the bound, not the data, fixes it), so that it does not make
  // every other parameter look undetermined.
  std::vector<Eigen::Index> kept;
  for (Eigen::Index j = 0; j < n; ++j) {
    const auto& spec = specs[static_cast<std::size_t>(j)];
    const bool collapsed = spec.transform == Transform::log && std::abs(dp_du[j]) < 1e-9 * std::abs(spec.initial);
    if (!collapsed && jac_p.col(j).allFinite()) kept.push_back(j);
  }
  if (static_cast<Eigen::Index>(kept.size()) == n || kept.empty()) {
    covariance_statistics(jac_p, result.residuals, result.std_errors, result.correlation, result.sigma);
    return result;
  }
  Eigen::MatrixXd jac_kept(m, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t k = 0; k < kept.size(); ++k) jac_kept.col(static_cast<Eigen::Index>(k)) = jac_p.col(kept[k]);
  Eigen::VectorXd se_kept;
  Eigen::MatrixXd corr_kept;
  covariance_statistics(jac_kept, result.residuals, se_kept, corr_kept, result.sigma);
  result.std_errors = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::infinity());
  result.correlation = Eigen::MatrixXd::Constant(n, n, std::numeric_limits<double>::quiet_NaN());
  for (Eigen::Index j = 0; j < n; ++j) result.correlation(j, j) = 1.0;
  for (std::size_t a = 0; a < kept.size(); ++a) {
    result.std_errors[kept[a]] = se_kept[static_cast<Eigen::Index>(a)];
    for (std::size_t b = 0; b < kept.size(); ++b)
      result.correlation(kept[a], kept[b]) = corr_kept(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
  }
  return result;
}

}  // namespace mcg::fit
