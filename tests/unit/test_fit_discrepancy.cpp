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

TEST(FitDiscrepancy, NothingToFindInAModelThatIsRight) {
  const DiscrepancyResult d =
      fit_discrepancy(model::Model{}, data_of(model::Model{}, 4.0), {7.0}, rpm_floor());
  EXPECT_TRUE(d.terms.empty());
  EXPECT_EQ(d.note, "no term of the library explains a clear part of the torque residual");
}

}  // namespace
}  // namespace mcg::fit
