// Transfer-function fit on analytically computed frequency responses.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

#include "common/error.hpp"
#include "fit/tf.hpp"
#include "model/model.hpp"
#include "signal/excitation.hpp"
#include "signal/spectrum.hpp"

namespace mcg::fit {
namespace {

using Complex = std::complex<double>;

/// Log-spaced response of g between f0 and f1 (Hz), optionally with multiplicative noise
/// of `sigma` nepers / rad on log G and a coherence column.
FrequencyResponse response_of(const std::function<Complex(Complex)>& g, double f0, double f1, int points,
                              double sigma = 0.0, std::uint64_t seed = 1) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  FrequencyResponse fr;
  fr.source = "<test>";
  for (int k = 0; k < points; ++k) {
    const double f = f0 * std::pow(f1 / f0, k / (points - 1.0));
    Complex h = g(Complex(0.0, 2.0 * std::numbers::pi * f));
    h *= std::exp(Complex(sigma * noise(rng), sigma * noise(rng)));
    fr.f_hz.push_back(f);
    fr.mag_db.push_back(20.0 * std::log10(std::abs(h)));
    fr.phase_deg.push_back(std::arg(h) * 180.0 / std::numbers::pi);
  }
  return fr;
}

Complex report_plant(Complex s) { return 16.557 / ((s / 65.0 + 1.0) * (s / 950.0 + 1.0)); }

// The report's second-order plant, exact data: poles, gain and the coefficient form of the
// report's Matlab appendix (den = [1.6194e-5 .016437 1]) come back.
TEST(FitTf, ReportPlantExactResponse) {
  const auto fit = fit_tf(response_of(report_plant, 0.5, 200.0, 60), {});
  ASSERT_EQ(fit.poles.size(), 2U);
  EXPECT_NEAR(fit.gain, 16.557, 1e-8);
  EXPECT_NEAR(fit.poles[0].corner_rad_s, 65.0, 1e-7);
  EXPECT_NEAR(fit.poles[1].corner_rad_s, 950.0, 1e-5);
  EXPECT_FALSE(fit.poles[0].complex_pair);
  ASSERT_EQ(fit.tf.den.size(), 3U);
  EXPECT_NEAR(fit.tf.den[0], 1.0 / (65.0 * 950.0), 1e-12);  // 1.6194e-5 in the report
  EXPECT_NEAR(fit.tf.den[1], 1.0 / 65.0 + 1.0 / 950.0, 1e-10);  // .016437 in the report
  EXPECT_DOUBLE_EQ(fit.tf.den[2], 1.0);
  EXPECT_NEAR(fit.tf.num[0], 16.557, 1e-8);
  EXPECT_EQ(format_factored(fit), "16.557/((s/65+1)*(s/950+1))");
  EXPECT_LT(fit.rms_mag_db, 1e-8);
  EXPECT_TRUE(fit.nls.converged);
}

// Noisy estimate (0.02 nepers ~ 0.17 dB, 1.1 deg per point): within a few standard errors,
// and the standard errors are of the size the noise implies.
TEST(FitTf, ReportPlantNoisyResponseWithinStandardErrors) {
  const auto fit = fit_tf(response_of(report_plant, 0.5, 200.0, 120, 0.02, 11), {});
  ASSERT_EQ(fit.poles.size(), 2U);
  EXPECT_NEAR(fit.gain, 16.557, 4.0 * fit.gain_se);
  EXPECT_NEAR(fit.poles[0].corner_rad_s, 65.0, 4.0 * fit.poles[0].corner_se);
  EXPECT_NEAR(fit.poles[1].corner_rad_s, 950.0, 4.0 * fit.poles[1].corner_se);
  EXPECT_GT(fit.poles[1].corner_se, 1.0);
  EXPECT_LT(fit.poles[1].corner_se, 60.0);
  EXPECT_LT(fit.gain_se / 16.557, 0.01);
  EXPECT_NEAR(fit.nls.sigma, 0.02, 0.004);
}

// A lightly damped pair with a zero and an integrator-free gain of 0.3:
// G = 0.3 (s/20 + 1) / ((s/300)^2 + 2 0.15 s/300 + 1) / (s/5 + 1).
TEST(FitTf, ResonantPlantWithZero) {
  const auto g = [](Complex s) {
    return 0.3 * (s / 20.0 + 1.0) / ((s / 300.0) * (s / 300.0) + 0.3 * s / 300.0 + 1.0) / (s / 5.0 + 1.0);
  };
  TfFitOptions options;
  options.poles = 3;
  options.zeros = 1;
  const auto fit = fit_tf(response_of(g, 0.1, 500.0, 200), options);
  ASSERT_EQ(fit.poles.size(), 2U);
  ASSERT_EQ(fit.zeros.size(), 1U);
  EXPECT_NEAR(fit.gain, 0.3, 1e-7);
  EXPECT_NEAR(fit.poles[0].corner_rad_s, 5.0, 1e-6);
  EXPECT_TRUE(fit.poles[1].complex_pair);
  EXPECT_NEAR(fit.poles[1].corner_rad_s, 300.0, 1e-5);
  EXPECT_NEAR(fit.poles[1].zeta, 0.15, 1e-7);
  EXPECT_NEAR(fit.zeros[0].corner_rad_s, 20.0, 1e-6);
  EXPECT_EQ(format_factored(fit), "0.3*(s/20+1)/((s/5+1)*((s/300)^2+0.3*(s/300)+1))");
}

// Coherence weights: points with coherence 0 are ignored, so a corrupted stretch with zero
// coherence does not move the fit.
TEST(FitTf, ZeroCoherencePointsAreIgnored) {
  auto fr = response_of(report_plant, 0.5, 200.0, 80);
  fr.coherence.assign(fr.f_hz.size(), 0.98);
  for (std::size_t k = 30; k < 40; ++k) {
    fr.mag_db[k] += 12.0;
    fr.coherence[k] = 0.0;
  }
  const auto fit = fit_tf(fr, {});
  EXPECT_NEAR(fit.poles[0].corner_rad_s, 65.0, 1e-6);
  EXPECT_NEAR(fit.gain, 16.557, 1e-7);
  EXPECT_EQ(fit.points, 70U);
}

// The report's Fig. 16-1 procedure on the nonlinear model: a log chirp of 2 V about 6 V,
// 0.5..200 Hz over 20 s, clutch engaged, generator open; Welch H1 from v to omega; two poles.
// The linearisation at the operating speed w0 has the closed form
//   G(s) = Kt / ((L s + R)(J s + B) + Kt Ke),  B = dF/dw at w0 (all friction elements),
// and the fit must land on it (16.9/((s/67+1)(s/888+1)) here); the report's
// 16.557/((s/65+1)(s/950+1)) is only near: its 950 rad/s is 7 % above the model's own pole.
TEST(FitTf, ReportPlantFromSimulatedChirp) {
  const double dt = 1e-3;
  std::vector<double> t;
  for (int k = 0; k < 20000; ++k) t.push_back(k * dt);
  const std::vector<double> chirp = signal::chirp_signal(t, 2.0, 0.5, 200.0, 20.0, signal::ChirpSpacing::log);
  model::Inputs in;
  in.t_s = t;
  for (double c : chirp) in.v_V.push_back(6.0 + c);
  in.clutch.assign(t.size(), 2.0);
  in.r_load_ohm.assign(t.size(), model::k_open_circuit);
  const model::Model rig;
  const model::Outputs out = model::simulate(rig, in);
  const std::size_t skip = 1000;  // start-up transient
  const std::span<const double> x(in.v_V.data() + skip, in.v_V.size() - skip);
  const std::span<const double> y(out.omega_rad_s.data() + skip, out.omega_rad_s.size() - skip);
  const signal::Response r = signal::welch_h1(x, y, dt, 2048, 0.5);
  FrequencyResponse fr;
  fr.source = "<chirp>";
  for (std::size_t k = 0; k < r.f_hz.size(); ++k) {
    if (r.f_hz[k] < 0.5 || r.f_hz[k] > 200.0 || !std::isfinite(std::abs(r.h[k]))) continue;
    fr.f_hz.push_back(r.f_hz[k]);
    fr.mag_db.push_back(signal::magnitude_db(r.h[k]));
    fr.phase_deg.push_back(std::arg(r.h[k]) * 180.0 / std::numbers::pi);
    fr.coherence.push_back(r.coherence[k]);
  }
  TfFitOptions options;
  options.fit_delay = true;
  const TfFit fit = fit_tf(fr, options);
  ASSERT_EQ(fit.poles.size(), 2U);

  // Closed form at the mean speed of the run.
  const auto& p = rig.params;
  double w0 = 0.0;
  for (std::size_t k = skip; k < out.omega_rad_s.size(); ++k) w0 += out.omega_rad_s[k];
  w0 /= static_cast<double>(out.omega_rad_s.size() - skip);
  const auto slope = [w0](const model::Friction& f) {
    return f.viscous[0] + 2.0 * f.viscous[1] * w0 + 3.0 * f.viscous[2] * w0 * w0;
  };
  const double b = slope(p.motor.friction) + slope(p.generator.friction) + slope(p.clutch_engaged);
  const double j = p.motor.J_kg_m2 + p.generator.J_kg_m2;
  const auto& m = p.motor;
  const double a2 = m.L_H * j;
  const double a1 = m.R_ohm * j + m.L_H * b;
  const double a0 = m.R_ohm * b + m.Kt_Nm_A * m.Ke_V_s_rad;
  const double disc = std::sqrt(a1 * a1 - 4.0 * a2 * a0);
  const double slow = (a1 - disc) / (2.0 * a2);
  const double fast = (a1 + disc) / (2.0 * a2);
  const double gain = m.Kt_Nm_A / a0;
  EXPECT_NEAR(fit.gain, gain, 0.02 * gain);
  EXPECT_NEAR(fit.poles[0].corner_rad_s, slow, 0.03 * slow);
  EXPECT_NEAR(fit.poles[1].corner_rad_s, fast, 0.1 * fast);  // partly traded against the delay
  // Near the report's numbers (its gain 16.557 and corners 65, 950 rad/s).
  EXPECT_NEAR(fit.gain, 16.557, 0.05 * 16.557);
  EXPECT_NEAR(fit.poles[0].corner_rad_s, 65.0, 0.1 * 65.0);
  EXPECT_NEAR(fit.poles[1].corner_rad_s, 950.0, 0.15 * 950.0);
  // The samples carry the zero-order hold of the inputs: about half a period of delay.
  EXPECT_NEAR(fit.delay_s, 0.5e-3, 0.15e-3);
}

TEST(FitTf, ErrorsNameTheProblem) {
  const auto fr = response_of(report_plant, 1.0, 10.0, 2);
  try {
    fit_tf(fr, {});
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "<test>: too short: 2 usable frequencies for 3 coefficients");
  }
  TfFitOptions options;
  options.zeros = 3;
  EXPECT_THROW(fit_tf(response_of(report_plant, 1.0, 10.0, 30), options), Error);
}

TEST(FitTf, ReadsFrequencyResponseTables) {
  std::istringstream in("f_hz,mag_db,phase_deg,coherence\n1,20,-10,0.9\n2,19,-20,1.2\n");
  const auto table = table::read(in, "bode.csv");
  try {
    read_frequency_response(table);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "bode.csv:3: column 'coherence': 1.2 is outside 0..1");
  }
}

// A board's bode file of an rpm counted over 16 ms is the plant's response times the window's mean
// W(s) = (1 - e^(-s T)) / (s T): read, W is divided out (the points near its zeros at 62.5 and 125 Hz
// left out and counted), and the fit gives the plant itself; the same data said to be another output
// keeps W, and its fit is off.
TEST(FitTf, RpmWindowIsDividedOutOfABoardResponse) {
  const auto plant = [](Complex s) { return 3000.0 / ((s / 60.0 + 1.0) * (s / 300.0 + 1.0)); };
  const double window_s = 0.016;
  const auto table_of = [&](const std::string& out) {
    std::ostringstream csv;
    csv << "# response: duty -> " << out << "\n# rpm_estimator: counts over 0.016 s window, 2048 counts/rev\n"
        << "f_hz,mag_db,phase_deg\n";
    for (int k = 1; k <= 128; ++k) {
      const double f = 0.9765625 * k;
      const Complex s(0.0, 2.0 * std::numbers::pi * f);
      const Complex h = plant(s) * (1.0 - std::exp(-s * window_s)) / (s * window_s);
      csv << fmt::format("{:.17g},{:.17g},{:.17g}\n", f, 20.0 * std::log10(std::abs(h)),
                         std::arg(h) * 180.0 / std::numbers::pi);
    }
    std::istringstream in(csv.str());
    return table::read(in, "bode.csv");
  };
  const FrequencyResponse fr = read_frequency_response(table_of("rpm"));
  EXPECT_DOUBLE_EQ(fr.output_window_s, 0.016);
  EXPECT_EQ(fr.window_zeros, 14U);  // |W| < 0.05: 59.6 .. 65.4 Hz and 119.1 .. 125 Hz
  EXPECT_EQ(fr.f_hz.size(), 114U);
  const TfFit fit = fit_tf(fr, {});
  EXPECT_NEAR(fit.gain, 3000.0, 1e-6 * 3000.0);
  ASSERT_EQ(fit.poles.size(), 2U);
  EXPECT_NEAR(fit.poles[0].corner_rad_s, 60.0, 1e-6 * 60.0);
  EXPECT_NEAR(fit.poles[1].corner_rad_s, 300.0, 1e-6 * 300.0);

  const FrequencyResponse kept = read_frequency_response(table_of("rpm_true"));
  EXPECT_EQ(kept.output_window_s, 0.0);
  EXPECT_EQ(kept.f_hz.size(), 128U);
  const TfFit off = fit_tf(kept, {});
  const auto near = [](double x, double want) { return std::abs(x - want) <= 0.05 * want; };
  const bool plant_found = off.poles.size() == 2 && near(off.poles[0].corner_rad_s, 60.0) &&
                           near(off.poles[1].corner_rad_s, 300.0) && near(off.gain, 3000.0);
  EXPECT_FALSE(plant_found) << off.poles.size() << " poles";
}

TEST(FitTf, PolynomialRoots) {
  const auto roots = polynomial_roots({2.0, -6.0, 4.0, 0.0});  // 2 s (s - 1)(s - 2)
  ASSERT_EQ(roots.size(), 3U);
  std::vector<double> re;
  for (const auto& r : roots) re.push_back(r.real());
  std::sort(re.begin(), re.end());
  EXPECT_NEAR(re[0], 0.0, 1e-15);
  EXPECT_NEAR(re[1], 1.0, 1e-12);
  EXPECT_NEAR(re[2], 2.0, 1e-12);
}

}  // namespace
}  // namespace mcg::fit
