// Levenberg-Marquardt wrapper: optimum and statistics against closed forms.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "common/error.hpp"
#include "fit/nls.hpp"

namespace mcg::fit {
namespace {

// Straight line y = a + b x: the least-squares optimum and its standard errors are known in
// closed form, se(b) = sigma / sqrt(Sxx), se(a) = sigma sqrt(1/N + xbar^2 / Sxx),
// corr(a, b) = -xbar / sqrt(Sxx / N + xbar^2).
TEST(FitNls, StraightLineMatchesOrdinaryLeastSquares) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.3);
  const int n = 200;
  Eigen::VectorXd x(n), y(n);
  for (int k = 0; k < n; ++k) {
    x[k] = 0.37 * k + 1.3;
    y[k] = 2.5 - 0.8 * x[k] + noise(rng);
  }
  const double xbar = x.mean();
  const double ybar = y.mean();
  const double sxx = (x.array() - xbar).square().sum();
  const double sxy = ((x.array() - xbar) * (y.array() - ybar)).sum();
  const double b = sxy / sxx;
  const double a = ybar - b * xbar;
  const double sigma = std::sqrt((y.array() - a - b * x.array()).square().sum() / (n - 2));

  const auto result = least_squares({{"a", 1.0}, {"b", 1.0}}, n, [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    r = p[0] + p[1] * x.array() - y.array();
  });
  ASSERT_TRUE(result.converged) << result.reason;
  EXPECT_NEAR(result.values[0], a, 1e-7);
  EXPECT_NEAR(result.values[1], b, 1e-8);
  EXPECT_NEAR(result.sigma, sigma, 1e-9);
  EXPECT_NEAR(result.std_errors[1], sigma / std::sqrt(sxx), 1e-6 * sigma / std::sqrt(sxx));
  EXPECT_NEAR(result.std_errors[0], sigma * std::sqrt(1.0 / n + xbar * xbar / sxx), 1e-6);
  EXPECT_NEAR(result.correlation(0, 1), -xbar / std::sqrt(sxx / n + xbar * xbar), 1e-6);
  EXPECT_EQ(result.names, (std::vector<std::string>{"a", "b"}));
}

// A log parameter stays positive and its standard error is expressed in physical units:
// y = A exp(-t / tau), tau = 0.0147 s (the report's time constant), exact data.
TEST(FitNls, LogParameterRecoversTimeConstant) {
  const int n = 100;
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, 0.0, 0.06);
  const Eigen::VectorXd y = 3.0 * (-t.array() / 0.0147).exp();
  const auto result = least_squares({{"A", 1.0, Transform::log}, {"tau_s", 0.1, Transform::log}}, n,
                                    [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
                                      r = p[0] * (-t.array() / p[1]).exp() - y.array();
                                    });
  ASSERT_TRUE(result.converged) << result.reason;
  EXPECT_NEAR(result.values[1], 0.0147, 1e-10);
  EXPECT_NEAR(result.values[0], 3.0, 1e-8);
  EXPECT_LT(result.cost, 1e-20);
}

// The point the solver stands on is simulated once: its start, the base of every forward-difference
// Jacobian and the optimum whose statistics are reported are looked up, not evaluated again
// (each evaluation of a grey-box fit is a whole simulation).
TEST(FitNls, NoPointIsEvaluatedTwice) {
  const int n = 100;
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, 0.0, 0.06);
  const Eigen::VectorXd y = 3.0 * (-t.array() / 0.0147).exp() + 0.2;
  std::vector<std::vector<double>> seen;
  const auto result = least_squares(
      {{"A", 1.0, Transform::log}, {"tau_s", 0.1, Transform::log}, {"c", 0.0, Transform::linear, 1.0}}, n,
      [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
        seen.emplace_back(p.data(), p.data() + p.size());
        r = p[0] * (-t.array() / p[1]).exp() + p[2] - y.array();
      });
  ASSERT_TRUE(result.converged) << result.reason;
  EXPECT_NEAR(result.values[1], 0.0147, 1e-9);
  EXPECT_GT(result.iterations, 3);
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(std::adjacent_find(seen.begin(), seen.end()), seen.end()) << "a point was evaluated twice";
}

// Broyden updates between finite-difference Jacobians (NlsOptions::broyden) reach the optimum
// of the finite-difference solver on fewer finite-difference Jacobians, and the statistics
// there come from one: values within 1e-7 relative, standard errors within 1e-5. (On this
// small problem the trial steps the updates cost outweigh the columns they save.)
TEST(FitNls, BroydenUpdatesReachTheSameOptimum) {
  const int n = 120;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.01);
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, 0.0, 0.08);
  Eigen::VectorXd y = 3.0 * (-t.array() / 0.0147).exp() + 0.2 + 1.5 * (t.array() * 90.0).sin() * t.array();
  for (Eigen::Index k = 0; k < n; ++k) y[k] += noise(rng);
  const std::vector<ParameterSpec> specs{{"A", 1.0, Transform::log},
                                         {"tau_s", 0.05, Transform::log},
                                         {"c", 0.0, Transform::linear, 1.0},
                                         {"b", 0.5, Transform::linear, 1.0}};
  std::vector<std::vector<double>> seen;
  const ResidualFunction f = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    seen.emplace_back(p.data(), p.data() + p.size());
    r = p[0] * (-t.array() / p[1]).exp() + p[2] + p[3] * (t.array() * 90.0).sin() * t.array() - y.array();
  };
  NlsOptions options;
  const NlsResult fd = least_squares(specs, n, f, options);
  const auto fd_points = static_cast<int>(seen.size());
  seen.clear();
  options.broyden = true;
  const NlsResult updated = least_squares(specs, n, f, options);
  ASSERT_TRUE(fd.converged) << fd.reason;
  ASSERT_TRUE(updated.converged) << updated.reason;
  for (Eigen::Index i = 0; i < fd.values.size(); ++i) {
    EXPECT_NEAR(updated.values[i], fd.values[i], 1e-7 * std::abs(fd.values[i]))
        << fd.names[static_cast<std::size_t>(i)];
    EXPECT_NEAR(updated.std_errors[i], fd.std_errors[i], 1e-5 * fd.std_errors[i]);
  }
  EXPECT_EQ(fd.broyden_jacobians, 0);
  EXPECT_GT(updated.broyden_jacobians, 0);
  EXPECT_LT(updated.fd_jacobians, fd.fd_jacobians);
  EXPECT_EQ(fd.simulations, fd_points);
  EXPECT_EQ(updated.simulations, static_cast<int>(seen.size()));
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(std::adjacent_find(seen.begin(), seen.end()), seen.end()) << "a point was evaluated twice";
}

// A time budget interrupts the solver: one already spent returns the start untouched; one that
// runs out inside an iteration (here, after the first Jacobian) stops it at once, at the last
// accepted point, with no further evaluation at all (the statistics' Jacobian is not spent:
// standard errors and correlations are NaN, and the result says it was stopped).
TEST(FitNls, StopInterruptsInsideAnIteration) {
  const int n = 100;
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, 0.0, 0.06);
  const Eigen::VectorXd y = 3.0 * (-t.array() / 0.0147).exp();
  int calls = 0;
  const auto residual = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    ++calls;
    r = p[0] * (-t.array() / p[1]).exp() - y.array();
  };
  const std::vector<ParameterSpec> specs{{"A", 1.0, Transform::log}, {"tau_s", 0.1, Transform::log}};
  NlsOptions options;
  options.threads = 1;
  options.stop = [] { return true; };
  const auto spent = least_squares(specs, n, residual, options);
  EXPECT_FALSE(spent.converged);
  EXPECT_EQ(spent.reason, "stopped early (time budget spent)");
  EXPECT_EQ(spent.values[0], 1.0);
  EXPECT_EQ(spent.values[1], 0.1);
  EXPECT_TRUE(spent.stopped);

  calls = 0;
  int calls_at_stop = -1;
  options.stop = [&] {
    if (calls >= 3 && calls_at_stop < 0) calls_at_stop = calls;
    return calls >= 3;
  };
  const auto cut = least_squares(specs, n, residual, options);
  EXPECT_FALSE(cut.converged);
  EXPECT_EQ(cut.reason, "stopped early (time budget spent)");
  EXPECT_EQ(cut.values[0], 1.0);
  EXPECT_EQ(cut.values[1], 0.1);
  // The residuals at the returned point are looked up, not simulated again.
  EXPECT_EQ(calls_at_stop, 3);
  EXPECT_EQ(calls, calls_at_stop);
  EXPECT_TRUE(cut.stopped);
  EXPECT_TRUE(cut.std_errors.array().isNaN().all());
  EXPECT_TRUE(std::isnan(cut.correlation(0, 1)));
  EXPECT_EQ(cut.correlation(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(cut.cost, cut.residuals.squaredNorm());

  // Without a stop the same solver moves off the start in its first iteration, with statistics.
  options.stop = nullptr;
  const auto full = least_squares(specs, n, residual, options);
  EXPECT_NE(full.values[1], 0.1);
  EXPECT_FALSE(full.stopped);
  EXPECT_TRUE(full.std_errors.allFinite());
}

TEST(FitNls, BudgetSpentIsNotConvergence) {
  NlsOptions options;
  options.max_evaluations = 3;
  const auto result = least_squares({{"k", 5.0, Transform::log}}, 3,
                                    [](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
                                      r << std::exp(-p[0]) - 0.5, std::exp(-2 * p[0]) - 0.25, p[0] * 0.0 + 0.01;
                                    },
                                    options);
  EXPECT_FALSE(result.converged);
  EXPECT_EQ(result.reason, "evaluation budget spent before convergence");
}

TEST(FitNls, RejectsTooFewResidualsAndNonPositiveLogStart) {
  const ResidualFunction f = [](const Eigen::VectorXd& p, Eigen::VectorXd& r) { r.setConstant(p.sum()); };
  EXPECT_THROW(
      {
        try {
          least_squares({{"a", 1.0}, {"b", 1.0}}, 1, f);
        } catch (const Error& e) {
          EXPECT_STREQ(e.what(), "too little data: 1 residuals for 2 free parameters");
          throw;
        }
      },
      Error);
  EXPECT_THROW(least_squares({{"J", 0.0, Transform::log}}, 4, f), Error);
}

// Two parameters that only enter as a sum: the data cannot tell them apart.
TEST(FitNls, UndeterminedDirectionGivesInfiniteStandardErrors) {
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(20, 0.0, 1.0);
  const auto result = least_squares({{"a", 1.0}, {"b", 2.0}, {"c", 0.5}}, 20,
                                    [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
                                      r = (p[0] + p[1]) * x.array() + p[2] - (4.0 * x.array() + 1.0 + 0.01 * x.array().sin());
                                    });
  EXPECT_TRUE(std::isinf(result.std_errors[0]));
  EXPECT_TRUE(std::isinf(result.std_errors[1]));
  EXPECT_TRUE(std::isfinite(result.std_errors[2]));
}

// The residual jumps just above the optimum: a finite-difference Jacobian sees the jump
// over its step and gives an absurdly small standard error; the check at 100 times the
// step finds that the residual is not smooth there.
TEST(FitNls, JumpAtTheOptimumIsRough) {
  const ResidualFunction f = [](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    for (Eigen::Index k = 0; k < r.size(); ++k) {
      r[k] = (p[0] - 2.0) + 0.01 * static_cast<double>(k % 7 - 3) + (p[0] > 2.0 + 1e-7 ? 1.0 : 0.0);
    }
  };
  const NlsResult r = least_squares({{"a", 2.0, Transform::linear, 0.0}}, 50, f);
  ASSERT_EQ(r.rough.size(), 1U);
  EXPECT_TRUE(r.rough[0]);
  EXPECT_LT(r.std_errors[0], 1e-6);
  // A smooth residual is not rough.
  const ResidualFunction g = [](const Eigen::VectorXd& p, Eigen::VectorXd& out) {
    for (Eigen::Index k = 0; k < out.size(); ++k) out[k] = (p[0] - 2.0) * (1.0 + 0.1 * static_cast<double>(k)) + 0.01 * static_cast<double>(k % 7 - 3);
  };
  EXPECT_FALSE(least_squares({{"a", 1.0, Transform::linear, 0.0}}, 50, g).rough[0]);
}

}  // namespace
}  // namespace mcg::fit
