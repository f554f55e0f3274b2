// The catalog-free discrepancy fit on effects the catalog does not have, written here as
// test-only shaft terms: the term's shape and coefficient come back, and a model without
// them gets none.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fit/discrepancy.hpp"
#include "model/model.hpp"

namespace mcg::fit {
namespace {

/// Quadratic drag, T = k[3] w |w|: nothing in the catalog has it.
double drag(const std::array<double, 4>& k, double, double w) { return k[3] * w * std::abs(w); }

/// A staircase of voltages on the motor alone, 1 kHz.
model::Inputs staircase(double base_V, double step_V, double hold_s, double duration_s) {
  model::Inputs in;
  for (std::size_t n = 0; n <= static_cast<std::size_t>(std::llround(duration_s / 1e-3)); ++n) {
    const double t = static_cast<double>(n) * 1e-3;
    in.t_s.push_back(t);
    in.v_V.push_back(base_V + step_V * static_cast<double>(static_cast<long>(t / hold_s) % 5));
    in.clutch.push_back(0.0);
    in.r_load_ohm.push_back(model::k_open_circuit);
  }
  return in;
}

Run measured(const model::Model& truth, model::Inputs in) {
  Run run;
  run.source = "test";
  run.outputs = {"rpm"};
  run.measured = {model::simulate(truth, in).rpm};
  run.inputs = std::move(in);
  return run;
}

/// Training and validation on different staircases from `base_V` up.
GapData data_of(const model::Model& truth, double base_V) {
  GapData data;
  data.train.push_back(measured(truth, staircase(base_V, base_V * 0.75, 0.3, 3.0)));
  ScoredRun validate;
  validate.run = measured(truth, staircase(base_V * 1.2, base_V * 0.6, 0.23, 3.0));
  data.validate.push_back(std::move(validate));
  return data;
}

/// The same with the generator engaged and its load switched every 0.4 s (open, 4 ohm, 1 ohm):
/// the current, and with it the torque, changes at every speed.
GapData loaded_data_of(const model::Model& truth, double base_V) {
  auto loaded = [](model::Inputs in) {
    for (std::size_t n = 0; n < in.t_s.size(); ++n) {
      in.clutch[n] = 2.0;
      const long slot = static_cast<long>(in.t_s[n] / 0.4) % 3;
      in.r_load_ohm[n] = slot == 0 ? model::k_open_circuit : slot == 1 ? 4.0 : 1.0;
    }
    return in;
  };
  GapData data;
  data.train.push_back(measured(truth, loaded(staircase(base_V, base_V * 0.75, 0.3, 3.0))));
  ScoredRun validate;
  validate.run = measured(truth, loaded(staircase(base_V * 1.2, base_V * 0.6, 0.23, 3.0)));
  data.validate.push_back(std::move(validate));
  return data;
}

std::vector<OutputFloor> rpm_floor() {
  OutputFloor f;
  f.output = "rpm";
  f.floor = 0.5;
  return {f};
}

TEST(FitDiscrepancy, FindsAQuadraticDragTheCatalogDoesNotHave) {
  model::Model truth;
  truth.shaft_terms.push_back({"drag", drag, {0.0, 0.0, 0.0, -4e-8}});
  const DiscrepancyResult d = fit_discrepancy(model::Model{}, data_of(truth, 4.0), {}, rpm_floor());
  ASSERT_EQ(d.terms.size(), 1U) << d.note;
  EXPECT_EQ(d.terms[0].basis, "w|w|");
  // Within 3 %: the current along the measured speed is integrated sample by sample.
  EXPECT_NEAR(d.terms[0].coefficient, -4e-8, 0.12e-8);
  EXPECT_GT(d.validation_explained_pct, 90.0);
  EXPECT_LT(d.rms_after_rpm, 0.1 * d.rms_before_rpm);
}

TEST(FitDiscrepancy, FindsAPositionRippleAtItsOrderAndPhase) {
  model::Model truth;
  truth.effects.push_back(model::parse_effect("cogging:T_c_Nm=0.0015,N_per_rev=9,phase_rad=0.7"));
  // At low speed, where the ripple shows in the speed (at high speed the rotor filters it out).
  const DiscrepancyResult d = fit_discrepancy(model::Model{}, data_of(truth, 1.6), {9.0, 4.0}, rpm_floor());
  ASSERT_EQ(d.terms.size(), 1U) << d.note;
  EXPECT_EQ(d.terms[0].basis, "sin(9 theta + phase)");
  // Within 15 % and 0.1 rad: near rest, where the ripple is largest, stick-slip windows are left out.
  EXPECT_NEAR(d.terms[0].coefficient, 0.0015, 0.000225);
  EXPECT_NE(d.terms[0].equation.find("theta + 0.7"), std::string::npos) << d.terms[0].equation;
}

/// Test-only effects outside every catalog, T = f(k, theta, w, i, t) (model::ShaftTerm::basis_it).
double once_per_rev(const std::array<double, 4>& k, double theta, double, double, double) {
  return k[3] * std::sin(theta + k[1]);
}
double current_ripple(const std::array<double, 4>& k, double theta, double, double i, double) {
  return k[3] * i * std::sin(k[0] * theta + k[1]);
}
double load_friction(const std::array<double, 4>& k, double, double w, double i, double) {
  return -k[3] * std::abs(i) * std::tanh(w / 0.5);
}
double fading_friction(const std::array<double, 4>& k, double, double w, double, double t) {
  return -k[3] * std::tanh(w / 0.5) * std::exp(-t / k[1]);
}

const DiscrepancyTerm* term(const DiscrepancyResult& d, const std::string& basis) {
  for (const DiscrepancyTerm& t : d.terms) {
    if (t.basis == basis) return &t;
  }
  return nullptr;
}

/// The term survives within two standard errors of the truth, and the model with the terms
/// does better on the held-out run than without them.
void expect_term(const DiscrepancyResult& d, const std::string& basis, double value, double phase = 0.0) {
  const DiscrepancyTerm* t = term(d, basis);
  ASSERT_NE(t, nullptr) << d.note << (d.terms.empty() ? "" : " first: " + d.terms[0].equation);
  EXPECT_FALSE(t->reading.empty());
  EXPECT_LT(std::abs(t->coefficient - value), 2.0 * t->std_error + 0.02 * std::abs(value)) << t->equation;
  EXPECT_LT(t->std_error, 0.2 * std::abs(value));
  if (t->order != 0.0) {
    EXPECT_LT(std::abs(t->phase_rad - phase), 2.0 * t->phase_se_rad + 0.02) << t->equation;
  }
  EXPECT_LT(d.rms_after_rpm, 0.5 * d.rms_before_rpm);
}

TEST(FitDiscrepancy, OncePerRevolutionTorque) {
  model::Model truth;
  truth.shaft_terms.push_back({"imbalance", nullptr, {1.0, 0.5, 0.0, 0.002}, once_per_rev});
  const DiscrepancyResult d = fit_discrepancy(model::Model{}, data_of(truth, 1.6), {}, rpm_floor());
  expect_term(d, "sin(1 theta + phase)", 0.002, 0.5);
  EXPECT_NE(term(d, "sin(1 theta + phase)")->reading.find("once per revolution"), std::string::npos);
}

TEST(FitDiscrepancy, CurrentProportionalRipple) {
  model::Model truth;
  truth.shaft_terms.push_back({"ripple", nullptr, {3.0, 0.4, 0.0, 0.004}, current_ripple});
  const DiscrepancyResult d = fit_discrepancy(model::Model{}, loaded_data_of(truth, 3.0), {3.0}, rpm_floor());
  expect_term(d, "i sin(3 theta + phase)", 0.004, 0.4);
}

TEST(FitDiscrepancy, LoadDependentFriction) {
  model::Model truth;
  truth.shaft_terms.push_back({"load friction", nullptr, {0.0, 0.0, 0.0, 0.002}, load_friction});
  const DiscrepancyResult d = fit_discrepancy(model::Model{}, loaded_data_of(truth, 4.0), {}, rpm_floor());
  expect_term(d, "|i| sign(w)", -0.002);
}

TEST(FitDiscrepancy, FrictionFadingOverTheRun) {
  model::Model truth;
  truth.shaft_terms.push_back({"warm-up", nullptr, {0.0, 0.99, 0.0, 0.003}, fading_friction});
  const DiscrepancyResult d = fit_discrepancy(model::Model{}, data_of(truth, 4.0), {}, rpm_floor());
  expect_term(d, "sign(w) exp(-t/0.99)", -0.003);
}

TEST(FitDiscrepancy, CoggingSeededFromItsHarmonic) {
  model::Model truth;
  truth.effects.push_back(model::parse_effect("cogging:T_c_Nm=0.0015,N_per_rev=9,phase_rad=1.3"));
  const DiscrepancyResult d = fit_discrepancy(model::Model{}, data_of(truth, 1.6), {9.0}, rpm_floor());
  const std::vector<model::Effect> seeds = catalog_seeds(d, model::Model{});
  ASSERT_EQ(seeds.size(), 1U) << d.note;
  EXPECT_EQ(seeds[0].name, "cogging");
  EXPECT_EQ(seeds[0].get("N_per_rev"), 9.0);
  EXPECT_NEAR(seeds[0].get("phase_rad"), 1.3, 0.1);
  EXPECT_NEAR(seeds[0].get("T_c_Nm"), 0.0015, 0.000225);
}

TEST(FitDiscrepancy, NothingToFindInAModelThatIsRight) {
  const DiscrepancyResult d =
      fit_discrepancy(model::Model{}, data_of(model::Model{}, 4.0), {7.0}, rpm_floor());
  EXPECT_TRUE(d.terms.empty());
  // A term that fits the training windows' noise leaves once simulated on the held-out run.
  EXPECT_TRUE(d.note == "no term of the library explains a clear part of the torque residual" ||
              d.note.find("none kept") != std::string::npos)
      << d.note;
}

}  // namespace
}  // namespace mcg::fit
