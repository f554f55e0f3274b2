// The parts of the discrepancy fit (see discrepancy.hpp for the method), shared between its files:
//   discrepancy.cpp        the shaft-torque library, its weak form and the sequence
//   discrepancy_side.cpp   the circuit and the readings: the voltage the armature circuit lacks and
//                          the errors of the measured current and speed
//   discrepancy_joint.cpp  the joint refit of the surviving torque terms with the nominal scales
// Internal to the fit library.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "fit/discrepancy.hpp"
#include "model/effects/compiled.hpp"

namespace mcg::fit::discrepancy_detail {

/// A run's measured motor speed (rad/s), angle (rad) and current (A, NaN where not measured);
/// the speed empty when it is not measured. `i_map` = {a, b}: the current the motor carries
/// is a i_measured + b (a reading's gain and offset taken out).
struct Measured {
  std::vector<double> w;
  std::vector<double> theta;
  std::vector<double> i;
};
Measured measured_of(const Run& run, std::array<double, 2> i_map = {1.0, 0.0});

/// The rows of a linear regression y = Phi xi (one row per weak-form window or sample).
struct Rows {
  std::vector<double> y;
  std::vector<std::vector<double>> phi;
};

/// One column of a library: how it reads, its coefficient's unit, what it is physically, and
/// whether it is the sin column of a harmonic (its cos column follows and joins with it).
struct Column {
  std::string text;
  std::string unit;
  std::string reading;
  double order = 0.0;  ///< harmonic order for sin/cos columns, else 0
  bool cos_of_pair = false;
  model::TermShape shape = model::TermShape::none;  ///< what it does, for the catalog's seeds
};

Eigen::MatrixXd matrix_of(const std::vector<std::vector<double>>& rows, const std::vector<std::size_t>& cols);

/// The least-squares solution of A x = y, its residual sum of squares and the standard errors
/// of x (covariance_statistics: infinite for a column the data do not determine).
struct Solved {
  Eigen::VectorXd x;
  Eigen::VectorXd se;
  double rss = 0.0;
};
Solved solve(const Eigen::MatrixXd& A, const Eigen::VectorXd& y);

/// Forward stepwise sparse regression: of the columns (a harmonic with its sin/cos pair) that
/// remove at least k_discrepancy_threshold of the training residual ||y||^2 and stand three
/// standard errors from 0, the one that lowers the training residual most joins, provided it
/// lowers the validation residual too (a column that does not carry over to held-out runs
/// describes the training runs' noise); one at a time, so of collinear columns only one
/// joins. Returns the selected columns (a pair as sin, cos).
std::vector<std::size_t> select_forward(const std::vector<Column>& library, const Rows& train,
                                        const Rows& validate);

/// The selected columns' coefficients in physical units with their standard errors, a sin/cos
/// pair combined into one harmonic (amplitude, phase), largest part of the fit first. `lead`
/// prefixes a harmonic's basis ("i " for a current-scaled one). `parts` receives each term's
/// norm of its part of the fit; `coef` the raw solution.
struct Described {
  std::vector<DiscrepancyTerm> terms;  ///< in the order of `set` (a pair as one)
  std::vector<double> parts;
  Solved fit;
  double train_pct = 0.0;
  double validation_pct = 0.0;
};
Described describe(const std::vector<Column>& library, const std::vector<std::size_t>& set, const Rows& train,
                   const Rows& validate, const std::function<std::string(std::size_t)>& lead);

/// "+ 0.0012" / "- 0.0012".
std::string signed_number(double v);

/// The circuit and the readings: terms found in the armature circuit's equation (a current
/// reading's offset and gain, confirmed by the torque equation; else a constant voltage and a
/// resistance error; a brush drop, a dead band of the drive), each kept only where the held-out
/// runs' circuit residual falls. `torque_rss` gives the validation torque residual ||y||^2 of
/// the weak form with the current mapped by {a, b}: a reading error shows in both equations.
struct Finding {
  std::vector<DiscrepancyTerm> terms;
  std::array<double, 2> i_map{1.0, 0.0};  ///< the current reading's correction, when confirmed
  std::size_t columns = 0;                ///< the library's columns that were tried
  /// Share of the validation circuit residual the terms explain, %; share of the validation
  /// torque residual the reading's correction removes, % (NaN: nothing kept, none confirmed).
  double validation_pct = std::numeric_limits<double>::quiet_NaN();
  double torque_pct = std::numeric_limits<double>::quiet_NaN();
};
Finding fit_circuit(const model::Compiled& c, const GapData& data,
                    const std::function<double(std::array<double, 2>)>& torque_rss);

/// The speed reading: measured - simulated rpm of `model` regressed on an offset, a gain and
/// the speed times the harmonics of the angle of `orders` (an encoder's eccentric disc); the
/// terms kept when the held-out runs' rpm RMS falls. `rms_rpm` receives that RMS (validation,
/// the readings' errors applied to the simulation), unchanged when nothing is kept.
Finding fit_speed_reading(const model::Model& model, const GapData& data, const std::vector<double>& orders,
                          double& rms_rpm);

/// The joint refit: the model's discrepancy shaft terms (coefficients, and the phases of the
/// harmonics) refitted together with the nominal scales and the catalog effects the model
/// carries, on the training runs' simulated outputs. The terms are the model's shaft terms from
/// `first_term` on, `phased` per term when it has a phase (k[1]). Returns the refitted model, per term its
/// coefficient and phase with their standard errors (the phase NaN for a term without one), and the freed
/// nominal parameters' names and values (`nominal`). Throws mcg::Error when the fit cannot run.
struct JointFit {
  model::Model model;
  std::vector<double> coefficient, coefficient_se, phase, phase_se;
  std::vector<std::pair<std::string, double>> nominal;
  bool converged = false;
};
JointFit joint_refit(const model::Model& model, std::size_t first_term, const std::vector<bool>& phased,
                     const GapData& data, const std::function<bool()>& stop);

}  // namespace mcg::fit::discrepancy_detail
