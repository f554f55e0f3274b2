// c2d against transforms derived by hand, at an awkward step size.
#include "common/error.hpp"
#include "linsys/c2d.hpp"
#include "linsys/parse.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace mcg::linsys {
namespace {

constexpr double k_tol = 1e-12;
constexpr double k_h = 0.031415926;  // awkward step, as in Drake's discretisation tests

/// num and den scaled so that den is monic, for comparing transfer functions.
void expect_tf(const Tf& h, const Poly& num, const Poly& den, double tol = k_tol) {
  ASSERT_TRUE(h.discrete());
  const Poly hd = trim(h.den);
  const Poly hn = trim(h.num);
  const double lead = hd.front();
  ASSERT_EQ(hd.size(), den.size()) << tf_text(h);
  ASSERT_EQ(hn.size(), num.size()) << tf_text(h);
  for (std::size_t i = 0; i < den.size(); ++i) EXPECT_NEAR(hd[i] / lead, den[i], tol) << "den " << i;
  for (std::size_t i = 0; i < num.size(); ++i) EXPECT_NEAR(hn[i] / lead, num[i], tol) << "num " << i;
}

Tf s_tf(const char* text) { return parse_tf(text, "test").tf; }

TEST(LinsysC2d, ZohFirstOrderMatchesAnalytic) {
  const double a = 3.7;
  const double e = std::exp(-a * k_h);
  const Tf h = c2d(s_tf("3.7/(s+3.7)"), k_h, C2dMethod::zoh, 0.0, "t");
  expect_tf(h, {1.0 - e}, {1.0, -e});
}

TEST(LinsysC2d, ZohSecondOrderMatchesPartialFractions) {
  // 1/((s+1)(s+2)) = 1/(s+1) − 1/(s+2); ZOH of 1/(s+p) is (1 − e^(−pT))/(p (z − e^(−pT))).
  const double e1 = std::exp(-k_h);
  const double e2 = std::exp(-2.0 * k_h);
  const double c1 = 1.0 - e1;
  const double c2 = (1.0 - e2) / 2.0;
  const Tf h = c2d(s_tf("1/((s+1)*(s+2))"), k_h, C2dMethod::zoh, 0.0, "t");
  expect_tf(h, {c1 - c2, -c1 * e2 + c2 * e1}, {1.0, -(e1 + e2), e1 * e2});
}

TEST(LinsysC2d, ZohFractionalDelayIsTheModifiedZTransform) {
  // e^(−1.5Ts)/(s+1): x[k+1] = e^(−T)x[k] + e^(−(T−θ))(1 − e^(−θ))u[k−2] + (1 − e^(−(T−θ)))u[k−1], θ = T/2.
  Tf g = s_tf("1/(s+1)");
  g.delay_s = 1.5 * k_h;
  const double th = 0.5 * k_h;
  const double e = std::exp(-k_h);
  const Tf h = c2d(g, k_h, C2dMethod::zoh, 0.0, "t");
  expect_tf(h, {1.0 - std::exp(-(k_h - th)), std::exp(-(k_h - th)) * (1.0 - std::exp(-th))}, {1.0, -e, 0.0, 0.0});
}

TEST(LinsysC2d, ZohWholeSampleDelayAddsPolesAtOrigin) {
  Tf g = s_tf("2/(s+2)");
  g.delay_s = 2.0 * k_h;
  const double e = std::exp(-2.0 * k_h);
  expect_tf(c2d(g, k_h, C2dMethod::zoh, 0.0, "t"), {1.0 - e}, {1.0, -e, 0.0, 0.0});
}

std::string c2d_error(const char* text, double delay_s, C2dMethod method) {
  Tf g = s_tf(text);
  g.delay_s = delay_s;
  try {
    c2d(g, 0.001, method, 0.0, "--plant");
  } catch (const mcg::Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(LinsysC2d, DelayInSamplesIsBoundedByTheDegreeLimit) {
  // Once a wrapped cast (length_error), undefined behaviour, or 17 million zeros.
  for (C2dMethod m : {C2dMethod::zoh, C2dMethod::tustin, C2dMethod::impulse}) {
    EXPECT_EQ(c2d_error("1/(s+1)", 3e6, m),
              std::string("--plant: delay 3000000 s is 3000000000 samples of 0.001 s; at most ") +
                  (m == C2dMethod::zoh ? "254" : "255") + " fit in the degree limit of 256");
  }
  EXPECT_EQ(c2d_error("1/(s+1)", 1e300, C2dMethod::zoh),
            "--plant: delay 1e+300 s is 1e+303 samples of 0.001 s; at most 254 fit in the degree limit of 256");
  EXPECT_EQ(c2d_error("1/(s+1)", std::numeric_limits<double>::infinity(), C2dMethod::foh),
            "--plant: delay inf s is inf samples of 0.001 s; at most 255 fit in the degree limit of 256");
  // At the limit: z^-(254+1) times a first-order denominator is degree 256.
  Tf g = s_tf("1/(s+1)");
  g.delay_s = 0.2545;
  EXPECT_EQ(trim(c2d(g, 0.001, C2dMethod::zoh, 0.0, "t").den).size(), 257u);
  g.delay_s = 0.255;
  EXPECT_EQ(trim(c2d(g, 0.001, C2dMethod::tustin, 0.0, "t").den).size(), 257u);
}

TEST(LinsysC2d, ZohKeepsFeedthrough) {
  // (s+3)/(s+1) = 1 + 2/(s+1).
  const double e = std::exp(-k_h);
  expect_tf(c2d(s_tf("(s+3)/(s+1)"), k_h, C2dMethod::zoh, 0.0, "t"), {1.0, -e + 2.0 * (1.0 - e)}, {1.0, -e});
}

TEST(LinsysC2d, FohOfIntegratorIsTrapezoidal) {
  expect_tf(c2d(s_tf("1/s"), k_h, C2dMethod::foh, 0.0, "t"), {k_h / 2.0, k_h / 2.0}, {1.0, -1.0});
}

TEST(LinsysC2d, FohFirstOrderMatchesHandDerivation) {
  // FOH of a/(s+a): H = (z−1)²/(Tz)·Z{a/(s²(s+a))}; with e = e^(−aT):
  // H = [(aT − 1 + e) z + (1 − e − aTe)] / (aT (z − e)).
  const double a = 2.5;
  const double e = std::exp(-a * k_h);
  const double at = a * k_h;
  expect_tf(c2d(s_tf("2.5/(s+2.5)"), k_h, C2dMethod::foh, 0.0, "t"), {(at - 1.0 + e) / at, (1.0 - e - at * e) / at},
            {1.0, -e});
}

TEST(LinsysC2d, TustinOfTheReportsPi) {
  // 4658(s/500 + 1)/s at 1 ms: Kp = 9.316, Ki = 4658, (Kp + KiT/2) z + (KiT/2 − Kp) over z − 1.
  const Tf h = c2d(s_tf("4658*(s/500+1)/s"), 0.001, C2dMethod::tustin, 0.0, "t");
  expect_tf(h, {11.645, -6.987}, {1.0, -1.0}, 1e-12);
}

TEST(LinsysC2d, TustinPrewarpMatchesAtTheWarpFrequency) {
  const Tf g = s_tf("100/(s^2 + 4*s + 100)");
  const double wp = 10.0;
  const Tf h = c2d(g, k_h, C2dMethod::tustin, wp, "t");
  EXPECT_NEAR(std::abs(h.freq(wp) - g.freq(wp)), 0.0, 1e-12);
  const Tf plain = c2d(g, k_h, C2dMethod::tustin, 0.0, "t");
  EXPECT_GT(std::abs(plain.freq(wp) - g.freq(wp)), 1e-3);
}

TEST(LinsysC2d, ImpulseInvariantFirstOrder) {
  const double e = std::exp(-3.0 * k_h);
  expect_tf(c2d(s_tf("1/(s+3)"), k_h, C2dMethod::impulse, 0.0, "t"), {k_h, 0.0}, {1.0, -e});
}

TEST(LinsysC2d, MatchedPutsInfiniteZerosAtMinusOneExceptOne) {
  const double e1 = std::exp(-k_h);
  const double e2 = std::exp(-2.0 * k_h);
  // K (z + 1)/((z − e1)(z − e2)), DC gain 1/2: K = (1 − e1)(1 − e2)/4.
  const double k = (1.0 - e1) * (1.0 - e2) / 4.0;
  expect_tf(c2d(s_tf("1/((s+1)*(s+2))"), k_h, C2dMethod::matched, 0.0, "t"), {k, k}, {1.0, -(e1 + e2), e1 * e2});
}

TEST(LinsysC2d, MatchedIntegratorMatchesTheVelocityGain) {
  // 1/(s(s+1)): H = K(z+1)/((z−1)(z−e)); lim (z−1)/T·H at z=1 = 1: K = T(1 − e)/2.
  const double e = std::exp(-k_h);
  const double k = k_h * (1.0 - e) / 2.0;
  expect_tf(c2d(s_tf("1/(s*(s+1))"), k_h, C2dMethod::matched, 0.0, "t"), {k, k}, {1.0, -(1.0 + e), e});
}

TEST(LinsysC2d, RejectsBadInput) {
  Tf g = s_tf("1/(s+1)");
  g.delay_s = 0.5 * k_h;
  EXPECT_THROW(c2d(g, k_h, C2dMethod::tustin, 0.0, "t"), mcg::Error);
  EXPECT_THROW(c2d(s_tf("s^2/(s+1)"), k_h, C2dMethod::zoh, 0.0, "t"), mcg::Error);
  EXPECT_THROW(c2d(s_tf("(s+2)/(s+1)"), k_h, C2dMethod::impulse, 0.0, "t"), mcg::Error);
  EXPECT_THROW(parse_method("bilinear", "--method"), mcg::Error);
}

TEST(LinsysC2d, CharpolyOfCompanionIsItsPolynomial) {
  const Tf g = s_tf("1/((s/60+1)*(s/850+1)*(s/1800+1))");
  const StateSpace ss = realise(g);
  const Poly p = charpoly(ss.a);
  const Poly want = from_roots({Complex(-60, 0), Complex(-850, 0), Complex(-1800, 0)});
  ASSERT_EQ(p.size(), want.size());
  for (std::size_t i = 0; i < p.size(); ++i) EXPECT_NEAR(p[i] / want[i], 1.0, 1e-12);
}

}  // namespace
}  // namespace mcg::linsys

namespace mcg::linsys {
namespace {

/// An independent oracle for 1/(s+1)^n: the sampled impulse response h_k in long double from
/// Taylor series of e^(A t) (no matrix exponential, no determinants), then N = den·H truncated,
/// den = (z − e^(−T))^n expanded in long double. `impulse`: h_k = T·g(kT); else ZOH.
std::vector<long double> oracle_numerator(int n, long double t, bool impulse) {
  using Vec = std::vector<long double>;
  // Companion form of (s+1)^n: x1' = −Σ c_j x_j + u, x_(i+1)' = x_i, y = x_n.
  Vec c(static_cast<std::size_t>(n) + 1, 1.0L);
  for (int k = 1; k <= n; ++k) c[static_cast<std::size_t>(k)] = c[static_cast<std::size_t>(k) - 1] * (n - k + 1) / k;
  auto apply_a = [&](const Vec& x) {
    Vec y(x.size(), 0.0L);
    for (int j = 0; j < n; ++j) y[0] -= c[static_cast<std::size_t>(j) + 1] * x[static_cast<std::size_t>(j)];
    for (int i = 1; i < n; ++i) y[static_cast<std::size_t>(i)] = x[static_cast<std::size_t>(i) - 1];
    return y;
  };
  // x(t) for x' = A x + b·w, x(0) = x0, by the Taylor series of e^(A t) and its integral.
  auto flow = [&](Vec x0, long double w) {
    Vec sum = x0;
    Vec term = x0;
    Vec bterm(static_cast<std::size_t>(n), 0.0L);
    bterm[0] = w * t;  // ∫ e^(Aσ) b dσ, first term b·t
    for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += bterm[i];
    for (int k = 1; k < 60; ++k) {
      term = apply_a(term);
      bterm = apply_a(bterm);
      for (auto& v : term) v *= t / k;
      for (auto& v : bterm) v *= t / (k + 1);
      for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += term[i] + bterm[i];
    }
    return sum;
  };
  Vec h(static_cast<std::size_t>(n) + 1, 0.0L);
  Vec x(static_cast<std::size_t>(n), 0.0L);
  if (impulse) {
    x[0] = 1.0L;  // x(0+) = b after a unit impulse
    for (int k = 0; k <= n; ++k) {
      h[static_cast<std::size_t>(k)] = t * x[static_cast<std::size_t>(n) - 1];
      x = flow(x, 0.0L);
    }
  } else {
    x = flow(x, 1.0L);  // one sample of a held unit input
    for (int k = 1; k <= n; ++k) {
      h[static_cast<std::size_t>(k)] = x[static_cast<std::size_t>(n) - 1];
      x = flow(x, 0.0L);
    }
  }
  const long double a = std::exp(-t);
  Vec den(static_cast<std::size_t>(n) + 1, 0.0L);
  den[0] = 1.0L;
  for (int k = 1; k <= n; ++k) {
    for (int j = k; j >= 1; --j) den[static_cast<std::size_t>(j)] -= a * den[static_cast<std::size_t>(j) - 1];
  }
  Vec num(static_cast<std::size_t>(n) + 1, 0.0L);
  for (int k = 0; k <= n; ++k) {
    for (int j = 0; j <= k; ++j) num[static_cast<std::size_t>(k)] += den[static_cast<std::size_t>(j)] * h[static_cast<std::size_t>(k - j)];
  }
  return num;  // descending powers of z, degree n (leading h_0 = 0 for ZOH)
}

void expect_oracle(const std::string& plant, int n, double dt, C2dMethod method) {
  const Tf h = c2d(parse_tf(plant, "t").tf, dt, method, 0.0, "t");
  const std::vector<long double> want = oracle_numerator(n, dt, method == C2dMethod::impulse);
  Poly got = trim(h.num);
  // The impulse numerator keeps its root at z = 0 (make_z cancels it only against a pole there).
  ASSERT_LE(got.size(), want.size()) << plant;
  Poly padded(want.size() - got.size(), 0.0);
  padded.insert(padded.end(), got.begin(), got.end());
  long double largest = 0.0L;
  for (long double w : want) largest = std::max(largest, std::abs(w));
  ASSERT_GT(largest, 0.0L);
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_NEAR(static_cast<double>(padded[i] / largest), static_cast<double>(want[i] / largest), 1e-9)
        << plant << " at dt " << dt << ", coefficient " << i;
  }
}

TEST(LinsysC2d, ShortSamplePeriodsKeepTheirNumerator) {
  // The old numerator, det(zI − Φ + ΓC) − det(zI − Φ), cancelled to exactly 0 here.
  expect_oracle("1/(s+1)^6", 6, 0.001, C2dMethod::zoh);
  expect_oracle("1/(s+1)^6", 6, 0.001, C2dMethod::impulse);
  expect_oracle("1/(s+1)^2", 2, 1e-9, C2dMethod::zoh);
  expect_oracle("1/(s+1)^3", 3, 1e-6, C2dMethod::zoh);
}

TEST(LinsysC2d, TinyGainsAndOverflowingPoles) {
  const Tf h = c2d(parse_tf("1e-300/(s+1)", "t").tf, 0.001, C2dMethod::zoh, 0.0, "t");
  ASSERT_EQ(trim(h.num).size(), 1U);
  EXPECT_NEAR(h.num[0] / (1e-300 * -std::expm1(-0.001)), 1.0, 1e-12);
  try {
    (void)c2d(parse_tf("1/(s-1e300)", "t").tf, 0.001, C2dMethod::zoh, 0.0, "--plant");
    FAIL() << "an overflowing pole was discretised";
  } catch (const mcg::Error& e) {
    EXPECT_EQ(std::string(e.what()), "--plant: e^(A*dt) overflows: a pole p with Re(p)*dt above 709 has no sampled value");
  }
}

}  // namespace
}  // namespace mcg::linsys

namespace mcg::linsys {
namespace {

TEST(LinsysC2d, SampledDenominatorIsTheMappedPoles) {
  // Poles −1, 0.7 and 16 at 1 s: Φ's eigenvalues span 0.37..8.9e6. det(zI − Φ)'s constant term
  // is −e^(T·Σp) = −e^15.7; expanding Φ's characteristic polynomial was 5e-10 off.
  const Tf h = c2d(parse_tf("1/((s+1)*(s-0.7)*(s-16))", "t").tf, 1.0, C2dMethod::zoh, 0.0, "t");
  const Poly d = trim(h.den);
  ASSERT_EQ(d.size(), 4U);
  EXPECT_NEAR(d[3] / d[0] / -std::exp(15.7), 1.0, 1e-14);
  EXPECT_NEAR(d[1] / d[0] / -(std::exp(-1.0) + std::exp(0.7) + std::exp(16.0)), 1.0, 1e-14);
}

TEST(LinsysC2d, RefusesWhatItCannotSampleAccurately) {
  // Found by fuzz_c2d: unstable poles near 16 and 18 ± 1.4j at 0.997 s. Every state-space
  // evaluation in double is 1e-4 off (a 80-digit reference); c2d answered it, now refuses.
  Tf g;
  g.num = {0.019792381547502673, 0.92136363599949411, 10.744121754052518, 0.49839515925895972};
  g.den = {1,
           -68.570643178888801,
           1762.5639179490554,
           -20123.396676690776,
           85951.404097417413,
           4567.0619336282543,
           -38259.742805785878};
  try {
    (void)c2d(g, 0.99726320655061007, C2dMethod::zoh, 0.0, "--plant");
    FAIL() << "an inaccurate sampled system was answered";
  } catch (const mcg::Error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot be discretised accurately"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mcg::linsys
