// The discrepancy fit beside the shaft: the armature circuit's equation and the readings of
// the measured current and speed (see discrepancy_parts.hpp).
//
// The circuit. With the measured speed w and current i, over 20 ms windows [a, b],
//   L (i(b) - i(a)) - int_a^b (v_b - R i - Ke w - V_b tanh(i / 0.01 A)) dt = int_a^b e dt,
// e the voltage the model's circuit lacks (v_b: the bridge's output per the model, held over
// each sample). Its library: a constant voltage c (the column -R (b - a): coefficient -c/R), a
// resistance error dR (the column -(L di + R int i): coefficient dR/R), a brush drop -V_b tanh(i / 0.01 A), a
// dead band of the drive -V_d tanh(v / (0.01 supply)) and a back-emf error -dKe w.
// A reading of the current i_m with gain g and offset o (i = a i_m + b, a = 1/g, b = -o/g)
// shows in the circuit as exactly that constant and that resistance error; it differs from
// them in that it shows in the torque equation too (Kt i with the wrong current), so the two
// columns are readings when taking them out of the measured current lowers the held-out
// torque residual, else voltages of the circuit.
//
// The speed. What the model still misses in the measured speed, rpm_m - rpm_sim, on an offset,
// a gain and rpm_sim sin(N theta), rpm_sim cos(N theta) (a speed reading in error periodic in
// the angle, in proportion to the speed: an eccentric encoder disc); per sample.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/checked.hpp"
#include "common/units.hpp"
#include "fit/discrepancy_parts.hpp"
#include "fit/gap_parts.hpp"

namespace mcg::fit::discrepancy_detail {

namespace {

enum CircuitColumn : std::size_t { c_offset, c_gain, c_brush, c_dead, c_emf, c_count };

/// Circuit rows of one run from row `first` on (runs that measure the current).
void circuit_windows(const model::Compiled& c, const Run& run, std::size_t first, Rows& out) {
  const Measured m = measured_of(run);
  if (m.w.empty()) return;
  const model::Inputs& in = run.inputs;
  const std::size_t rows = in.t_s.size();
  if (rows < 2 || std::none_of(m.i.begin(), m.i.end(), [](double x) { return std::isfinite(x); })) return;
  const double dt_typ = (in.t_s.back() - in.t_s.front()) / static_cast<double>(rows - 1);
  const auto width = clamp_to_integer(std::round(k_discrepancy_window_s / dt_typ), std::size_t{4},
                                      std::numeric_limits<std::size_t>::max());
  const model::Machine& mm = c.p.motor;
  const double supply = c.p.supply_V;
  // The model's circuit at row n: the bridge's output v_b (held over the sample, as the plant
  // applies it) and the R it uses.
  auto bridge = [&](std::size_t n, double& R, double& emf_share) {
    const double d = c.circuit.duty(std::clamp(in.v_V[n], -supply, supply) / supply);
    R = mm.R_ohm + c.circuit.R_series_ohm + std::abs(d) * c.circuit.R_duty_ohm;
    emf_share = c.circuit.emf_share(d);
    return d * supply;
  };
  for (std::size_t a = first; a + width < rows; a += width) {
    const std::size_t b = a + width;
    bool ok = true;
    for (std::size_t n = a; n <= b && ok; ++n) ok = std::isfinite(m.w[n]) && std::isfinite(m.i[n]);
    if (!ok) continue;
    double lacking = 0.0;
    std::vector<double> row(c_count, 0.0);
    for (std::size_t n = a; n < b; ++n) {
      const double dt = in.t_s[n + 1] - in.t_s[n];
      const double h = 0.5 * dt;
      double R = 0.0, emf_share = 1.0;
      const double v_b = bridge(n, R, emf_share);
      // The current is sampled about as fast as it settles (L/R near a sample), so the circuit
      // is taken over each sample as the model makes it: i relaxes from i(n) towards the level
      // i_ss it reaches i(n+1) on, and the back-emf it relaxes against is the speed weighted as
      // the exponential weighs it, at the fraction f = 1/(1 - decay) - L/(R dt) of the sample
      // (the speed moves linearly across it); then L di + R int i dt = R i_ss dt exactly.
      const double decay = std::exp(-R * dt / mm.L_H);
      const double i_ss = (m.i[n + 1] - decay * m.i[n]) / (1.0 - decay);
      const double f = 1.0 / (1.0 - decay) - mm.L_H / (R * dt);
      const double w_eff = m.w[n] + f * (m.w[n + 1] - m.w[n]);
      lacking += dt * (R * i_ss + emf_share * mm.Ke_V_s_rad * w_eff - v_b) +
                 h * c.circuit.V_sat_V *
                     (std::tanh(m.i[n] / c.circuit.i_sat_A) + std::tanh(m.i[n + 1] / c.circuit.i_sat_A));
      row[c_offset] -= dt * R;
      row[c_gain] -= dt * R * i_ss;
      row[c_brush] -= h * (std::tanh(m.i[n] / 0.01) + std::tanh(m.i[n + 1] / 0.01));
      row[c_dead] -= dt * std::tanh(in.v_V[n] / (0.01 * supply));
      row[c_emf] -= dt * w_eff;
    }
    out.y.push_back(lacking);
    out.phi.push_back(std::move(row));
  }
}

/// Share of the torque residual a reading's correction must remove to count as one.
constexpr double k_reading_confirms = k_discrepancy_threshold;

}  // namespace

Finding fit_circuit(const model::Compiled& c, const GapData& data,
                    const std::function<double(std::array<double, 2>)>& torque_rss) {
  Finding out;
  if (!gap_detail::measures_current(data.train)) return out;
  Rows train;
  Rows validate;
  for (const Run& run : data.train) circuit_windows(c, run, 0, train);
  for (const ScoredRun& sr : data.validate) circuit_windows(c, sr.run, sr.first_scored, validate);
  out.columns = c_count;
  if (train.y.size() < std::max(k_discrepancy_min_windows, std::size_t{c_count} + 1)) return out;
  const double R = c.p.motor.R_ohm + c.circuit.R_series_ohm;
  const std::vector<Column> library = {
      {"1", "A", "", 0.0, false},
      {"R int i", "1", "", 0.0, false},
      {"tanh(i/0.01)", "V", "a voltage drop against the current in the motor circuit: brush contact drop",
       0.0, false, model::TermShape::current_drop},
      {"tanh(v/0.01 supply)", "V",
       "a voltage lost from the drive's output in its direction: a dead band of the drive", 0.0, false,
       model::TermShape::drive_dead_band},
      {"w", "V s/rad", "a voltage proportional to speed: the back-emf constant differs from the model's", 0.0,
       false},
  };
  const std::vector<std::size_t> set = select_forward(library, train, validate);
  if (set.empty()) return out;
  const Described d = describe(library, set, train, validate, [](std::size_t) { return std::string(); });
  double a = 1.0;
  double b = 0.0;
  double se_a = 0.0;
  double se_b = 0.0;
  for (std::size_t j = 0; j < set.size(); ++j) {
    if (set[j] == c_gain) {
      a = 1.0 + d.terms[j].coefficient;
      se_a = d.terms[j].std_error;
    } else if (set[j] == c_offset) {
      b = d.terms[j].coefficient;
      se_b = d.terms[j].std_error;
    }
  }
  // Which of the offset and the gain the torque equation confirms as a reading's: the
  // correction (of both, or of either) that lowers the held-out torque residual most.
  bool offset_read = false;
  bool gain_read = false;
  if (a != 1.0 || b != 0.0) {
    const double raw = torque_rss({1.0, 0.0});
    double best = (1.0 - k_reading_confirms) * raw;
    for (const auto& [use_gain, use_offset] : {std::pair{true, true}, {true, false}, {false, true}}) {
      if ((use_gain && a == 1.0) || (use_offset && b == 0.0)) continue;
      const double r = torque_rss({use_gain ? a : 1.0, use_offset ? b : 0.0});
      if (raw > 0.0 && r < best) {
        best = r;
        gain_read = use_gain;
        offset_read = use_offset;
      }
    }
    if (gain_read || offset_read) out.torque_pct = 100.0 * (1.0 - best / raw);
  }
  out.i_map = {gain_read ? a : 1.0, offset_read ? b : 0.0};
  out.validation_pct = d.validation_pct;
  for (std::size_t j = 0; j < set.size(); ++j) {
    DiscrepancyTerm t = d.terms[j];
    t.place = "circuit";
    if (set[j] == c_offset && offset_read) {
      // i = a i_m + b: the reading's offset o = -b/a A.
      t.place = "current reading";
      t.basis = "current offset";
      t.coefficient = -b / out.i_map[0];
      t.std_error = se_b / out.i_map[0];
      t.reading = "an offset of the current reading: the sensor's zero";
      t.equation = fmt::format("i_measured = i {} A", signed_number(t.coefficient));
    } else if (set[j] == c_offset) {
      t.basis = "constant voltage";
      t.unit = "V";
      t.coefficient = -R * b;
      t.std_error = R * se_b;
      t.reading = "a constant voltage in the motor circuit: an offset of the drive's output";
      t.equation = fmt::format("{} V in the motor circuit", signed_number(t.coefficient));
    } else if (set[j] == c_gain && gain_read) {
      t.place = "current reading";
      t.basis = "current gain";
      t.coefficient = 1.0 / a;
      t.std_error = se_a / (a * a);
      t.reading = "a scale error of the current reading: the sensor's gain or shunt";
      t.equation = fmt::format("i_measured = {:.4g} i", t.coefficient);
    } else if (set[j] == c_gain) {
      t.basis = "resistance";
      t.unit = "ohm";
      t.coefficient = R * (a - 1.0);
      t.std_error = R * se_a;
      t.reading = "a resistance the model's motor circuit lacks: winding temperature, brushes or wiring";
      t.equation = fmt::format("{} ohm * i in the motor circuit", signed_number(t.coefficient));
    } else {
      t.equation =
          fmt::format("{} {} * -{} in the motor circuit", signed_number(t.coefficient), t.unit, t.basis);
    }
    out.terms.push_back(std::move(t));
  }
  return out;
}

Finding fit_speed_reading(const model::Model& model, const GapData& data, const std::vector<double>& orders,
                          double& rms_rpm) {
  Finding out;
  std::vector<Column> library = {
      {"rpm offset", "rpm", "an offset of the speed reading", 0.0, false},
      {"rpm gain", "1", "a scale error of the speed reading: counts per revolution or a gear ratio", 0.0,
       false},
  };
  for (double order : orders) {
    const std::string reading =
        order == 1.0 ? "the speed reading errs once per revolution in proportion to the speed: an eccentric "
                       "encoder disc"
                     : fmt::format(
                           "the speed reading errs {:g} times per revolution in proportion to the speed: "
                           "uneven encoder lines",
                           order);
    library.push_back({fmt::format("rpm sin({:g} theta)", order), "1", reading, order, false});
    library.push_back({fmt::format("rpm cos({:g} theta)", order), "1", reading, order, true});
  }
  out.columns = library.size();
  // Per sample of a run from `first` on: measured - simulated rpm and the columns.
  auto rows_of = [&](const Run& run, std::size_t first, Rows& rows) {
    std::size_t o_rpm = run.outputs.size();
    for (std::size_t o = 0; o < run.outputs.size(); ++o) {
      if (run.outputs[o] == "rpm") o_rpm = o;
    }
    if (o_rpm == run.outputs.size()) return;
    const auto sim = simulate_as_measured(model, run);
    const model::Outputs plant = model::simulate(model, run.inputs);
    for (std::size_t n = first; n < run.inputs.t_s.size(); ++n) {
      const double y = run.measured[o_rpm][n];
      const double s = sim[o_rpm][n];
      if (!std::isfinite(y) || !std::isfinite(s)) continue;
      std::vector<double> row = {1.0, s};
      for (double order : orders) {
        row.push_back(s * std::sin(order * plant.theta_rad[n]));
        row.push_back(s * std::cos(order * plant.theta_rad[n]));
      }
      rows.y.push_back(y - s);
      rows.phi.push_back(std::move(row));
    }
  };
  Rows train;
  Rows validate;
  for (const Run& run : data.train) rows_of(run, 0, train);
  for (const ScoredRun& sr : data.validate) rows_of(sr.run, sr.first_scored, validate);
  if (train.y.size() < k_discrepancy_min_windows || validate.y.empty()) return out;
  const std::vector<std::size_t> set = select_forward(library, train, validate);
  if (set.empty()) return out;
  const Described d =
      describe(library, set, train, validate, [](std::size_t) { return std::string("rpm "); });
  const Eigen::Map<const Eigen::VectorXd> Yv(validate.y.data(), static_cast<Eigen::Index>(validate.y.size()));
  const double before = std::sqrt(Yv.squaredNorm() / static_cast<double>(Yv.size()));
  const double after =
      std::sqrt((Yv - matrix_of(validate.phi, set) * d.fit.x).squaredNorm() / static_cast<double>(Yv.size()));
  if (!(after < before)) return out;
  rms_rpm *= after / before;
  for (std::size_t j = 0; j < d.terms.size(); ++j) {
    DiscrepancyTerm t = d.terms[j];
    t.place = "speed reading";
    if (t.basis == "rpm gain") t.coefficient += 1.0;
    out.terms.push_back(in_speed_unit(std::move(t), SpeedUnit{}));
  }
  return out;
}

}  // namespace mcg::fit::discrepancy_detail

namespace mcg::fit {

DiscrepancyTerm in_speed_unit(DiscrepancyTerm t, const SpeedUnit& unit) {
  if (t.place != "speed reading") return t;
  const std::string& col = unit.column;
  if (t.basis == "rpm gain") {
    t.equation = fmt::format("{0}_measured = {1:.4g} {0}", col, t.coefficient);
  } else if (t.basis == "rpm offset") {
    t.coefficient *= unit.per_rpm;
    t.std_error *= unit.per_rpm;
    t.unit = unit.name;
    t.equation = fmt::format("{0}_measured = {0} {1} {2}", col,
                             discrepancy_detail::signed_number(t.coefficient), unit.name);
  } else {
    t.equation = fmt::format("{0}_measured = {0} (1 {1} * sin({2:g} theta {3} rad))", col,
                             discrepancy_detail::signed_number(t.coefficient), t.order,
                             discrepancy_detail::signed_number(t.phase_rad));
  }
  return t;
}

}  // namespace mcg::fit
