// The catalog-free discrepancy fit (see discrepancy.hpp for the method).
#include "fit/discrepancy.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/checked.hpp"
#include "common/demand.hpp"
#include "common/error.hpp"
#include "fit/discrepancy_parts.hpp"
#include "fit/gap_parts.hpp"
#include "model/effects/compiled.hpp"

namespace mcg::fit {

using namespace discrepancy_detail;

namespace {

// Library bases, T = basis(k, theta, w, i, t) with the coefficient in k[3] (model::ShaftTerm's
// convention): the shaft's angle and speed, the motor current and the time of the run.
using Basis = double (*)(const std::array<double, 4>&, double, double, double, double);

double b_const(const std::array<double, 4>& k, double, double, double, double) { return k[3]; }
double b_sign(const std::array<double, 4>& k, double, double w, double, double) {
  return k[3] * std::tanh(w / k[0]);
}
double b_w(const std::array<double, 4>& k, double, double w, double, double) { return k[3] * w; }
double b_w_abs_w(const std::array<double, 4>& k, double, double w, double, double) {
  return k[3] * w * std::abs(w);
}
double b_w3(const std::array<double, 4>& k, double, double w, double, double) { return k[3] * w * w * w; }
double b_stribeck(const std::array<double, 4>& k, double, double w, double, double) {
  return k[3] * std::tanh(w / k[0]) * std::exp(-std::pow(std::abs(w) / k[1], k[2]));
}
double b_sin(const std::array<double, 4>& k, double theta, double, double, double) {
  return k[3] * std::sin(k[0] * theta + k[1]);
}
/// Kt i: a torque-constant error, or a gain error of a measured current.
double b_i(const std::array<double, 4>& k, double, double, double i, double) { return k[3] * i; }
/// |i| sign(w): friction that grows with the load the current carries.
double b_abs_i(const std::array<double, 4>& k, double, double w, double i, double) {
  return k[3] * std::abs(i) * std::tanh(w / k[0]);
}
/// i sin(N theta + phase): a torque constant that varies with the angle (commutation ripple).
double b_i_sin(const std::array<double, 4>& k, double theta, double, double i, double) {
  return k[3] * i * std::sin(k[0] * theta + k[1]);
}
/// sign(w) exp(-t/tau): a friction level that fades over the run (bearings warming up).
double b_decay(const std::array<double, 4>& k, double, double w, double, double t) {
  return k[3] * std::tanh(w / k[0]) * std::exp(-t / k[1]);
}
/// A voltage V (k[3]) against the current in the armature circuit, as the torque it costs:
/// -(Kt/R) V tanh(i / 0.01 A), k[0] = Kt/R (brush_drop's shape).
double b_drop(const std::array<double, 4>& k, double, double, double i, double) {
  return -k[0] * k[3] * std::tanh(i / model::k_brush_smooth_i_A);
}

/// A term of the torque library: its column and its basis with the basis' numbers (k[3] = 1).
struct Candidate {
  Column col;
  Basis basis = nullptr;
  std::array<double, 4> k{0.0, 0.0, 0.0, 1.0};
  /// A voltage V_d lost from the drive's output in its direction, as the torque it costs:
  /// -(Kt/R) V_d tanh(v / (0.01 supply)), k[0] = Kt/R, k[1] = 0.01 supply (no basis: the
  /// plant's bridge deadband is its simulation).
  bool dead_band = false;
};

double dead_band_torque(const std::array<double, 4>& k, double v) {
  return -k[0] * k[3] * std::tanh(v / k[1]);
}

/// Weak-form rows of one run from row `first` on: y (the torque integral the model lacks) and
/// the library's integrals, one row per window in which the shaft moves throughout. The
/// measured current is read through `i_map` (a reading's gain and offset taken out).
void windows(const model::Compiled& c, const Run& run, std::size_t first,
             const std::vector<Candidate>& library, double w_max, std::array<double, 2> i_map,
             Rows& rows_out) {
  const Measured m = measured_of(run, i_map);
  if (m.w.empty()) return;
  const model::Inputs& in = run.inputs;
  const std::size_t rows = in.t_s.size();
  if (rows < 2) return;
  const double dt_typ = (in.t_s.back() - in.t_s.front()) / static_cast<double>(rows - 1);
  const auto width = clamp_to_integer(std::round(k_discrepancy_window_s / dt_typ), std::size_t{4},
                                      std::numeric_limits<std::size_t>::max());
  const model::Machine& mm = c.p.motor;
  const model::Machine& mg = c.p.generator;
  const double R = mm.R_ohm + c.circuit.R_series_ohm;
  // The current along the measured speed (measured where it is).
  std::vector<double> i(rows, 0.0);
  for (std::size_t n = 0; n + 1 < rows; ++n) {
    const double cur = std::isfinite(m.i[n]) ? m.i[n] : i[n];
    i[n] = cur;
    const double v = std::clamp(in.v_V[n], -c.p.supply_V, c.p.supply_V);
    const double w = std::isfinite(m.w[n]) ? m.w[n] : 0.0;
    const double i_ss = (v - mm.Ke_V_s_rad * w) / R;
    i[n + 1] = i_ss + (cur - i_ss) * std::exp(-R * (in.t_s[n + 1] - in.t_s[n]) / mm.L_H);
  }
  if (std::isfinite(m.i[rows - 1])) i[rows - 1] = m.i[rows - 1];
  auto torque = [&](std::size_t n) {
    const int clutch = static_cast<int>(in.clutch[n]);
    const model::Friction& f = clutch == 2 ? c.rigid : c.motor_side[static_cast<std::size_t>(clutch)];
    const double w = m.w[n];
    const double dir = w > 0.0 ? 1.0 : -1.0;
    double T = mm.Kt_Nm_A * i[n] - dir * c.kinetic(f, std::abs(w)) +
               c.extra_motor_torque(m.theta[n], w, i[n], in.t_s[n]);
    if (clutch == 2 && std::isfinite(in.r_load_ohm[n])) {
      T -= mg.Kt_Nm_A * mg.Ke_V_s_rad * w / (mg.R_ohm + in.r_load_ohm[n]);
    }
    return T;
  };
  // Near rest the shaft may be held by static friction while the estimator still reports a
  // speed: windows stay above three counts of the estimator (or 1 % of the top speed) and
  // keep one direction.
  double w_min = 0.01 * w_max;
  if (run.rpm_estimator) {
    w_min = std::max(w_min, 3.0 * 2.0 * std::numbers::pi /
                                (run.rpm_estimator->counts_per_rev * run.rpm_estimator->window_s) *
                                run.gear_ratio);
  }
  for (std::size_t a = first; a + width < rows; a += width) {
    const std::size_t b = a + width;
    bool ok = true;
    for (std::size_t n = a; n <= b && ok; ++n) {
      ok = std::isfinite(m.w[n]) && std::abs(m.w[n]) >= w_min && (m.w[n] > 0.0) == (m.w[a] > 0.0) &&
           in.clutch[n] == in.clutch[a] && in.r_load_ohm[n] == in.r_load_ohm[a];
    }
    if (!ok) continue;
    const double J = in.clutch[a] == 2.0 ? c.J_total : mm.J_kg_m2;
    double integral = 0.0;
    std::vector<double> row(library.size(), 0.0);
    for (std::size_t n = a; n < b; ++n) {
      const double h = 0.5 * (in.t_s[n + 1] - in.t_s[n]);
      integral += h * (torque(n) + torque(n + 1));
      for (std::size_t k = 0; k < library.size(); ++k) {
        const Candidate& cand = library[k];
        row[k] += h * (cand.dead_band
                           ? 2.0 * dead_band_torque(cand.k, in.v_V[n])  // held over the sample
                           : cand.basis(cand.k, m.theta[n], m.w[n], i[n], in.t_s[n]) +
                                 cand.basis(cand.k, m.theta[n + 1], m.w[n + 1], i[n + 1], in.t_s[n + 1]));
      }
    }
    rows_out.y.push_back(J * (m.w[b] - m.w[a]) - integral);
    rows_out.phi.push_back(std::move(row));
  }
}

/// The torque library for top speed `w_max` over runs of `t_span` s and the angle `orders`.
std::vector<Candidate> torque_library(const model::Model& reference, double w_max, double t_span,
                                      const std::vector<double>& angle_orders) {
  const double eps = 0.01 * w_max;
  const model::Machine& mm = reference.params.motor;
  using Shape = model::TermShape;
  const auto plain = [](std::string text, std::string unit, Basis basis, std::array<double, 4> k,
                        std::string reading, Shape shape = Shape::none) {
    return Candidate{{std::move(text), std::move(unit), std::move(reading), 0.0, false, shape}, basis, k};
  };
  std::vector<Candidate> library = {
      plain("1", "N m", b_const, {0.0, 0.0, 0.0, 1.0},
            "a constant torque: a load, or an offset of a measured current"),
      plain("sign(w)", "N m", b_sign, {eps, 0.0, 0.0, 1.0}, "against the motion: Coulomb friction",
            Shape::sign),
      plain("w", "N m s/rad", b_w, {0.0, 0.0, 0.0, 1.0}, "proportional to speed: viscous friction"),
      plain("w|w|", "N m s^2/rad^2", b_w_abs_w, {0.0, 0.0, 0.0, 1.0},
            "quadratic in speed: windage, a fan or fluid drag"),
      plain("w^3", "N m s^3/rad^3", b_w3, {0.0, 0.0, 0.0, 1.0},
            "cubic in speed: drag rising faster than quadratic"),
      plain("i", "N m/A", b_i, {0.0, 0.0, 0.0, 1.0},
            "scales with the current: a torque-constant error or a current-sensor gain"),
      plain("|i| sign(w)", "N m/A", b_abs_i, {eps, 0.0, 0.0, 1.0},
            "friction that grows with the load the current carries", Shape::abs_current_sign),
      plain("-(Kt/R) tanh(i/0.01)", "V", b_drop, {mm.Kt_Nm_A / mm.R_ohm, 0.0, 0.0, 1.0},
            "a voltage drop against the current in the motor circuit: brush contact drop",
            Shape::current_drop),
  };
  Candidate dead = plain("-(Kt/R) tanh(v/0.01 supply)", "V", nullptr,
                         {mm.Kt_Nm_A / mm.R_ohm, 0.01 * reference.params.supply_V, 0.0, 1.0},
                         "a voltage lost from the drive's output in its direction: a dead band of the drive",
                         Shape::drive_dead_band);
  dead.dead_band = true;
  library.push_back(std::move(dead));
  // Stribeck-like drops at a twentieth and a fifth of the top speed, exponential and Gaussian.
  for (double scale : {0.05, 0.2}) {
    const double ws = scale * w_max;
    const std::string reading = "friction falling from rest with speed: Stribeck";
    library.push_back(
        plain(fmt::format("sign(w) exp(-|w|/{:.3g})", ws), "N m", b_stribeck, {eps, ws, 1.0, 1.0}, reading));
    library.push_back(plain(fmt::format("sign(w) exp(-(w/{:.3g})^2)", ws), "N m", b_stribeck,
                            {eps, ws, 2.0, 1.0}, reading));
  }
  // Friction levels that fade over a run, on a grid of a tenth, a third and all of its span.
  for (double share : {0.1, 0.33, 1.0}) {
    const double tau = share * t_span;
    if (!(tau > 0.0)) continue;
    library.push_back(
        plain(fmt::format("sign(w) exp(-t/{:.3g})", tau), "N m", b_decay, {eps, tau, 0.0, 1.0},
              fmt::format("a friction level that fades during the run (tau {:.3g} s): warm-up", tau)));
  }
  // Angle harmonics: once per revolution always, and the residual's strongest orders; each
  // as a torque and as a current-scaled torque, as its sin and cos pair (the cos is the sin a
  // quarter turn on).
  std::vector<double> orders = {1.0};
  for (double order : angle_orders) {
    if (order != 1.0) orders.push_back(order);
  }
  const auto add_harmonic = [&](const std::string& prefix, const char* unit, Basis basis, double order,
                                const std::string& per) {
    const Shape shape = basis == b_sin ? Shape::angle_harmonic : Shape::none;
    library.push_back({{fmt::format("{}sin({:g} theta)", prefix, order), unit, per, order, false, shape},
                       basis,
                       {order, 0.0, 0.0, 1.0}});
    library.push_back({{fmt::format("{}cos({:g} theta)", prefix, order), unit, per, order, true, shape},
                       basis,
                       {order, std::numbers::pi / 2.0, 0.0, 1.0}});
  };
  for (double order : orders) {
    add_harmonic("", "N m", b_sin, order,
                 order == 1.0
                     ? "once per revolution: an imbalance, a bent shaft or an eccentric load"
                     : fmt::format("{:g} per revolution: cogging or a load periodic in the angle", order));
  }
  for (double order : orders) {
    add_harmonic(
        "i ", "N m/A", b_i_sin, order,
        fmt::format("scales with the current, {:g} per revolution: torque ripple (Kt varying with the angle)",
                    order));
  }
  return library;
}

/// What the model leaves of the validation speed RMS, in noise floors, above which the speed
/// reading's errors are looked for (below, the rest is the noise's).
constexpr double k_reading_above_floor = 1.2;

/// The described terms of `set` and the reference model with them as shaft torques.
struct TorqueTerms {
  Described d;
  model::Model model;
};

TorqueTerms torque_terms(const std::vector<Candidate>& library, const std::vector<std::size_t>& set,
                         const Rows& train, const Rows& validate, const model::Model& reference) {
  std::vector<Column> cols;
  for (const Candidate& cand : library) cols.push_back(cand.col);
  TorqueTerms out;
  out.d = describe(cols, set, train, validate, [&](std::size_t k) {
    return library[k].basis == b_i_sin ? std::string("i ") : std::string();
  });
  out.model = reference;
  std::size_t q = 0;
  for (std::size_t j = 0; j < set.size(); ++j) {
    const Candidate& cand = library[set[j]];
    if (cand.col.cos_of_pair) continue;
    const DiscrepancyTerm& t = out.d.terms[q++];
    if (cand.dead_band) {
      // Simulated as the bridge's deadband (duty lost per period) when the model has none.
      if (t.coefficient > 0.0 && !reference.effect("hbridge")) {
        model::Effect e = model::default_effect("hbridge");
        e.set("R_on_ohm", 0.0);
        e.set("deadband", std::min(t.coefficient / reference.params.supply_V, 0.3));
        out.model.effects.push_back(std::move(e));
      }
      continue;
    }
    std::array<double, 4> k = cand.k;
    if (cand.col.order != 0.0) k[1] = t.phase_rad;
    k[3] = t.coefficient;
    out.model.shaft_terms.push_back({t.equation, nullptr, k, cand.basis});
  }
  return out;
}

/// The terms of `set` largest part first.
std::vector<DiscrepancyTerm> ranked(const Described& d) {
  std::vector<std::size_t> order(d.terms.size());
  for (std::size_t q = 0; q < order.size(); ++q) order[q] = q;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t x, std::size_t z) { return d.parts[x] > d.parts[z]; });
  std::vector<DiscrepancyTerm> out;
  for (std::size_t q : order) out.push_back(d.terms[q]);
  return out;
}

/// Backward pruning on the held-out runs: a term (a harmonic with its pair) whose removal, the
/// rest refitted, does not raise the validation speed RMS leaves. Returns the RMS of what stays.
double prune_held_out(const std::vector<Candidate>& library, std::vector<std::size_t>& active,
                      const Rows& train, const Rows& validate, const model::Model& reference,
                      const GapData& data, const std::vector<OutputFloor>& floors, std::size_t f_rpm,
                      std::vector<std::string>& dropped) {
  auto held_out = [&](const std::vector<std::size_t>& set) {
    return gap_detail::evaluate(torque_terms(library, set, train, validate, reference).model, data, floors)
        .rms[f_rpm];
  };
  auto without = [&](const std::vector<std::size_t>& set, std::size_t j) {
    std::vector<std::size_t> rest;
    const bool pair = library[set[j]].col.order != 0.0;
    for (std::size_t q = 0; q < set.size(); ++q) {
      if (q != j && !(pair && q == j + 1)) rest.push_back(set[q]);
    }
    return rest;
  };
  double rms_all = held_out(active);
  while (active.size() > 1) {
    std::size_t drop = active.size();
    double best = rms_all;
    for (std::size_t j = 0; j < active.size(); ++j) {
      if (library[active[j]].col.cos_of_pair) continue;
      const std::vector<std::size_t> rest = without(active, j);
      if (rest.empty()) continue;
      const double r = held_out(rest);
      if (r <= best) {
        best = r;
        drop = j;
      }
    }
    if (drop == active.size()) break;
    dropped.push_back(library[active[drop]].col.text);
    active = without(active, drop);
    rms_all = best;
  }
  return rms_all;
}

/// The joint refit of the kept torque terms with the nominal scales and the reference's
/// catalog effects; adopted when the held-out runs gain over the terms stacked on the model.
void refit_jointly(DiscrepancyResult& out, std::size_t first_term, const GapData& data,
                   const std::vector<OutputFloor>& floors, std::size_t f_rpm,
                   const std::function<bool()>& stop) {
  JointFit joint;
  try {
    std::vector<bool> phased;
    for (std::size_t s = first_term; s < out.model.shaft_terms.size(); ++s) {
      const Basis basis = out.model.shaft_terms[s].basis_it;
      phased.push_back(basis == b_sin || basis == b_i_sin);
    }
    joint = joint_refit(out.model, first_term, phased, data, stop);
  } catch (const Error& e) {
    out.joint = fmt::format("not run: {}", e.what());
    return;
  }
  const double rms = gap_detail::evaluate(joint.model, data, floors).rms[f_rpm];
  std::string nominal;
  for (const auto& [name, value] : joint.nominal) nominal += fmt::format(", {} {:.4g}", name, value);
  if (!(rms < out.rms_after_rpm)) {
    out.joint = fmt::format(
        "refitted with{} the held-out rpm RMS is {:.3g}, not below {:.3g}: the terms stay as fitted",
        nominal.empty() ? " the terms alone," : nominal.substr(1) + ",", rms, out.rms_after_rpm);
    return;
  }
  out.joint = fmt::format("held-out rpm RMS {:.3g} -> {:.3g}{}{}", out.rms_after_rpm, rms,
                          nominal.empty() ? "" : " with", nominal.empty() ? "" : nominal.substr(1));
  out.rms_after_rpm = rms;
  // The shaft terms are the model's last ones, in the order of the terms that are torques.
  const std::size_t first = joint.model.shaft_terms.size() - joint.coefficient.size();
  for (DiscrepancyTerm& t : out.terms) {
    if (t.place != "shaft") continue;
    for (std::size_t s = first; s < joint.model.shaft_terms.size(); ++s) {
      model::ShaftTerm& st = joint.model.shaft_terms[s];
      if (st.equation != t.equation) continue;
      const std::size_t j = s - first;
      t.coefficient = joint.coefficient[j];
      t.std_error = joint.coefficient_se[j];
      if (t.order != 0.0) {
        t.phase_rad = joint.phase[j];
        t.phase_se_rad = joint.phase_se[j];
        const std::string lead = t.basis.rfind("i ", 0) == 0 ? "i " : "";
        t.equation = fmt::format("{} {} * {}sin({:g} theta {} rad)", signed_number(t.coefficient), t.unit,
                                 lead, t.order, signed_number(t.phase_rad));
      } else {
        const std::string basis = t.basis;
        t.equation = fmt::format("{} {} * {}", signed_number(t.coefficient), t.unit, basis);
      }
      st.equation = t.equation;
      break;
    }
  }
  out.model = std::move(joint.model);
}

/// The shaft stage on `data`: the torque library's weak form (the measured current through
/// `i_map`), forward selection, backward pruning on the held-out runs and the joint refit. Fills
/// `out`'s terms, model, windows, shares, rms_after_rpm (from rms_before_rpm), note and joint.
void shaft_stage(const model::Model& reference, const GapData& data, const std::vector<Candidate>& library,
                 double w_max, std::array<double, 2> i_map, const std::vector<OutputFloor>& floors,
                 std::size_t f_rpm, const std::function<bool()>& stop, DiscrepancyResult& out) {
  const model::Compiled c(reference);
  Rows train;
  Rows validate;
  for (const Run& run : data.train) windows(c, run, 0, library, w_max, i_map, train);
  for (const ScoredRun& sr : data.validate)
    windows(c, sr.run, sr.first_scored, library, w_max, i_map, validate);
  out.train_windows = train.y.size();
  out.validation_windows = validate.y.size();
  // Forward selection fits a few columns at a time: the windows must outnumber the library and
  // be enough (k_discrepancy_min_windows) to tell a term from noise at three standard errors.
  const std::size_t needed = std::max(k_discrepancy_min_windows, library.size() + 1);
  if (train.y.size() < needed) {
    out.note = fmt::format("too few windows in which the shaft turns ({} of 20 ms; {} needed)",
                           train.y.size(), needed);
    return;
  }
  std::vector<Column> cols;
  for (const Candidate& cand : library) cols.push_back(cand.col);
  std::vector<std::size_t> active = select_forward(cols, train, validate);
  if (active.empty()) {
    out.note = "no term of the library explains a clear part of the torque residual";
    return;
  }
  // Kept only where the held-out runs gain: the model with the terms is simulated on the
  // validation runs; the terms leave altogether when it does not beat the reference there.
  const double rms_all =
      prune_held_out(library, active, train, validate, reference, data, floors, f_rpm, out.dropped);
  if (!(rms_all < out.rms_before_rpm)) {
    out.note = fmt::format(
        "the terms found ({}) do not lower the validation speed RMS once simulated with the model; none kept",
        library[active.front()].col.text);
    return;
  }
  TorqueTerms kept = torque_terms(library, active, train, validate, reference);
  out.terms = ranked(kept.d);
  out.train_explained_pct = kept.d.train_pct;
  out.validation_explained_pct = kept.d.validation_pct;
  out.model = std::move(kept.model);
  out.rms_after_rpm = rms_all;
  refit_jointly(out, reference.shaft_terms.size(), data, floors, f_rpm, stop);
}

/// `data` with the speed reading's errors (fit_speed_reading's terms) taken out of the measured
/// speed: rpm = (rpm_m - offset) / (gain + sum e sin(N theta + phase)), theta the measured angle.
GapData read_right(const GapData& data, const std::vector<DiscrepancyTerm>& reading) {
  GapData out = data;
  auto correct = [&](Run& run) {
    const Measured m = measured_of(run);
    for (std::size_t o = 0; o < run.outputs.size(); ++o) {
      if (run.outputs[o] != "rpm") continue;
      for (std::size_t n = 0; n < run.measured[o].size(); ++n) {
        double offset = 0.0;
        double gain = 1.0;
        for (const DiscrepancyTerm& t : reading) {
          if (t.basis == "rpm offset") offset = t.coefficient;
          if (t.basis == "rpm gain") gain = t.coefficient;
          if (t.order != 0.0) gain += t.coefficient * std::sin(t.order * m.theta[n] + t.phase_rad);
        }
        run.measured[o][n] = (run.measured[o][n] - offset) / gain;
      }
    }
  };
  for (Run& run : out.train) correct(run);
  for (ScoredRun& sr : out.validate) correct(sr.run);
  return out;
}

/// A reading error explains the speed instead of torques when the held-out rpm RMS it leaves
/// is below this share of what the torques (with a reading error after them) leave.
constexpr double k_reading_first_wins = 0.8;

/// The validation torque residual ||y||^2 of the weak form on `c` with the measured current
/// read through i_map (fit_circuit's confirmation).
double torque_rss(const model::Compiled& c, const GapData& data, double w_max, std::array<double, 2> i_map) {
  Rows validate;
  for (const ScoredRun& sr : data.validate) windows(c, sr.run, sr.first_scored, {}, w_max, i_map, validate);
  return Eigen::Map<const Eigen::VectorXd>(validate.y.data(), static_cast<Eigen::Index>(validate.y.size()))
      .squaredNorm();
}

/// The circuit's finding on `reference`. A current reading's gain g shows in the circuit as a
/// resistance R/g, so a reference that scales its resistance (param_mismatch's R_scale s, as
/// a gap candidate fitted it) may carry the reading's gain as s = 1/g: the circuit is then
/// fitted again at the resistance as given, and when there the torque equation confirms a gain
/// of the reading, that finding stands and its gain term names the scale it is the same fact as.
Finding circuit_stage(const model::Model& reference, const GapData& data, double w_max) {
  const model::Compiled c(reference);
  const auto rss_on = [&](const model::Compiled& on) {
    return [&on, &data, w_max](std::array<double, 2> i_map) { return torque_rss(on, data, w_max, i_map); };
  };
  Finding found = fit_circuit(c, data, rss_on(c));
  const model::Effect* scales = reference.effect("param_mismatch");
  if (scales == nullptr || scales->get("R_scale") == 1.0) return found;
  const bool has_gain = std::any_of(found.terms.begin(), found.terms.end(),
                                    [](const DiscrepancyTerm& t) { return t.basis == "current gain"; });
  if (has_gain) return found;
  const double s = scales->get("R_scale");
  model::Model given = reference;
  for (model::Effect& e : given.effects) {
    if (e.name == "param_mismatch") e.set("R_scale", 1.0);
  }
  const model::Compiled cg(given);
  Finding at_given = fit_circuit(cg, data, rss_on(cg));
  const auto gain = std::find_if(at_given.terms.begin(), at_given.terms.end(),
                                 [](const DiscrepancyTerm& t) { return t.basis == "current gain"; });
  // The reading's correction must explain the torque at least as well as the scaled circuit's.
  if (gain == at_given.terms.end() ||
      torque_rss(c, data, w_max, at_given.i_map) > torque_rss(c, data, w_max, found.i_map)) {
    return found;
  }
  at_given.columns += found.columns;
  gain->reading = fmt::format(
      "a scale error of the current reading: the sensor's gain or shunt; the fitted R_scale {:.4g} is this "
      "gain (1/{:.4g}), not the resistance",
      s, gain->coefficient);
  return at_given;
}

}  // namespace

DiscrepancyResult fit_discrepancy(const model::Model& reference, const GapData& data,
                                  const std::vector<double>& angle_orders,
                                  const std::vector<OutputFloor>& floors, const std::function<bool()>& stop) {
  DiscrepancyResult out;
  out.model = reference;
  const std::size_t f_rpm = gap_detail::floor_index(floors, "rpm");
  if (f_rpm == std::string::npos) {
    out.note = "the discrepancy fit needs the measured speed";
    return out;
  }
  out.floor_rpm = floors[f_rpm].floor;
  // Speed scales of the library from the training runs.
  double w_max = 0.0;
  for (const Run& run : data.train) {
    for (double w : measured_of(run).w) {
      if (std::isfinite(w)) w_max = std::max(w_max, std::abs(w));
    }
  }
  if (!(w_max > 0.0)) {
    out.note = "the shaft never turns in the training runs";
    return out;
  }
  double t_span = 0.0;
  for (const Run& run : data.train) {
    if (!run.inputs.t_s.empty()) t_span = std::max(t_span, run.inputs.t_s.back());
  }
  const std::vector<Candidate> library = torque_library(reference, w_max, t_span, angle_orders);
  out.library_size = library.size();
  out.rms_before_rpm = gap_detail::evaluate(reference, data, floors).rms[f_rpm];
  out.rms_after_rpm = out.rms_before_rpm;

  // The circuit first: a current reading's gain and offset, once confirmed, are taken out of
  // the measured current before the torque the model lacks is computed from it.
  const Finding circuit = circuit_stage(reference, data, w_max);
  out.library_size += circuit.columns;
  std::vector<double> orders = {1.0};
  for (double order : angle_orders) {
    if (order != 1.0) orders.push_back(order);
  }
  // The shaft, then the speed reading's errors in what the model with its terms still misses
  // (looked for only where that stands above the noise) ...
  DiscrepancyResult shaft_first = out;
  shaft_stage(reference, data, library, w_max, circuit.i_map, floors, f_rpm, stop, shaft_first);
  if (shaft_first.rms_after_rpm > k_reading_above_floor * out.floor_rpm) {
    Finding speed = fit_speed_reading(shaft_first.model, data, orders, shaft_first.rms_after_rpm);
    out.library_size += speed.columns;
    for (DiscrepancyTerm& t : speed.terms) shaft_first.terms.push_back(std::move(t));
  }
  // ... or the speed reading's errors first, taken out of the measured speed, then the shaft:
  // whichever leaves the held-out runs less (the shaft's unless the reading's is clearly so).
  DiscrepancyResult reading_first = out;
  Finding reading;
  if (out.rms_before_rpm > k_reading_above_floor * out.floor_rpm) {
    double rms_read = out.rms_before_rpm;
    reading = fit_speed_reading(reference, data, orders, rms_read);
  }
  out = std::move(shaft_first);
  if (!reading.terms.empty()) {
    const GapData corrected = read_right(data, reading.terms);
    reading_first.rms_before_rpm = gap_detail::evaluate(reference, corrected, floors).rms[f_rpm];
    reading_first.rms_after_rpm = reading_first.rms_before_rpm;
    shaft_stage(reference, corrected, library, w_max, circuit.i_map, floors, f_rpm, stop, reading_first);
    if (reading_first.rms_after_rpm < k_reading_first_wins * out.rms_after_rpm) {
      for (DiscrepancyTerm& t : reading.terms) reading_first.terms.push_back(std::move(t));
      reading_first.rms_before_rpm = out.rms_before_rpm;
      out = std::move(reading_first);
    }
  }
  for (const DiscrepancyTerm& t : circuit.terms) out.terms.push_back(t);
  if (!circuit.terms.empty()) {
    out.circuit_validation_pct = circuit.validation_pct;
    out.reading_torque_pct = circuit.torque_pct;
  }
  if (!out.terms.empty()) out.note.clear();
  return out;
}

namespace {

bool has_place(const DiscrepancyResult& d, std::string_view place) {
  return std::any_of(d.terms.begin(), d.terms.end(),
                     [&](const DiscrepancyTerm& t) { return t.place == place; });
}

/// The terms that act beside the shaft, as the circuit share's subject.
std::string circuit_subject(const DiscrepancyResult& d) {
  const bool circuit = has_place(d, "circuit");
  const bool reading = has_place(d, "current reading");
  return circuit && reading ? "the circuit and current-reading terms"
         : reading          ? "the current reading's terms"
                            : "the circuit terms";
}

}  // namespace

std::string explained_text(const DiscrepancyResult& d, bool summary, const SpeedUnit& unit) {
  const auto g = [](double v, int digits) { return fmt::format("{:.{}g}", v, digits); };
  std::vector<std::string> parts;
  if (has_place(d, "shaft")) {
    parts.push_back(summary ? fmt::format("explains {} % of the torque residual in validation",
                                          g(d.validation_explained_pct, 3))
                            : fmt::format("explains {:.0f} % of the torque residual in training, {:.0f} % in "
                                          "validation",
                                          d.train_explained_pct, d.validation_explained_pct));
  }
  if (std::isfinite(d.circuit_validation_pct)) {
    parts.push_back(fmt::format(
        "{} explain {} % of the motor circuit's voltage residual in validation", circuit_subject(d),
        summary ? g(d.circuit_validation_pct, 3) : fmt::format("{:.0f}", d.circuit_validation_pct)));
  }
  if (std::isfinite(d.reading_torque_pct)) {
    parts.push_back(
        fmt::format("correcting the current reading removes {} % of the torque residual",
                    summary ? g(d.reading_torque_pct, 3) : fmt::format("{:.0f}", d.reading_torque_pct)));
  }
  const bool speed_moved = has_place(d, "shaft") || has_place(d, "speed reading");
  const double before = unit.per_rpm * d.rms_before_rpm;
  const double after = unit.per_rpm * d.rms_after_rpm;
  const double floor = unit.per_rpm * d.floor_rpm;
  const std::string& col = unit.column;
  if (summary) {
    parts.push_back(speed_moved
                        ? fmt::format("validation {} RMS {} -> {}", col, g(before, 4), g(after, 4))
                        : fmt::format("validation {} RMS {} (not theirs to move)", col, g(before, 4)));
  } else {
    // Decimals enough to show the noise floor to three figures (two for rpm's usual floors; a
    // linear axis' m/s floor of 9e-5 needs seven).
    const double size = floor > 0.0 ? floor : before;
    const int dec = std::isfinite(size) && size > 0.0
                        ? std::clamp(2 - static_cast<int>(std::floor(std::log10(size))), 2, 9)
                        : 2;
    parts.push_back(speed_moved
                        ? fmt::format("added to the model, validation {} RMS {:.{}f} -> {:.{}f} {} (noise "
                                      "floor {:.{}f})",
                                      col, before, dec, after, dec, unit.name, floor, dec)
                        : fmt::format("the simulated speed is not theirs to move: validation {} RMS "
                                      "{:.{}f} {} (noise floor {:.{}f})",
                                      col, before, dec, unit.name, floor, dec));
  }
  std::string out;
  for (std::size_t k = 0; k < parts.size(); ++k) out += (k == 0 ? "" : "; ") + parts[k];
  return out;
}

std::string closing_text(const DiscrepancyResult& d) {
  if (has_place(d, "shaft") || has_place(d, "speed reading")) {
    const double f2 = d.floor_rpm * d.floor_rpm;
    const double before2 = d.rms_before_rpm * d.rms_before_rpm;
    const double rest = before2 - f2;
    const double closed = rest > 0.0 ? 100.0 * (before2 - d.rms_after_rpm * d.rms_after_rpm) / rest : 0.0;
    return fmt::format(", closing {:.0f} % of the rest", std::clamp(closed, -999.0, 100.0));
  }
  std::string out;
  if (std::isfinite(d.circuit_validation_pct)) {
    out += fmt::format(", {} closing {:.0f} % of the motor circuit's voltage residual", circuit_subject(d),
                       d.circuit_validation_pct);
  }
  if (std::isfinite(d.reading_torque_pct)) {
    out += fmt::format(", correcting the current reading removes {:.0f} % of the torque residual",
                       d.reading_torque_pct);
  }
  return out;
}

std::vector<model::Effect> catalog_seeds(const DiscrepancyResult& result, const model::Model& reference) {
  std::vector<model::Effect> seeds;
  const auto seeded = [&](std::string_view name) {
    return reference.effect(name) != nullptr ||
           std::any_of(seeds.begin(), seeds.end(), [&](const model::Effect& e) { return e.name == name; });
  };
  // Which shape starts which effect, and how, is the effect's plan's (model/effects/); each
  // term starts at most one effect, the first of the catalog that takes its values.
  for (const DiscrepancyTerm& t : result.terms) {
    if (t.shape == model::TermShape::none) continue;
    const model::TermValues values{t.coefficient, t.order, t.phase_rad};
    bool started = false;
    for (const model::EffectSpec& spec : model::effect_catalog()) {
      if (started || !spec.plan.candidate || seeded(spec.name)) continue;
      for (const model::TermSeed& rule : spec.plan.seeded_by) {
        if (rule.shape != t.shape || started) continue;
        const std::vector<std::pair<std::string, double>> start = rule.start(values, reference.params);
        if (start.empty()) continue;
        model::Effect e = model::default_effect(spec.name);
        for (const auto& [key, value] : start) {
          const auto p = std::find_if(spec.params.begin(), spec.params.end(),
                                      [&](const model::EffectParamSpec& ps) { return ps.name == key; });
          MCG_DEMAND(p != spec.params.end());
          e.set(key, std::clamp(value, p->lower, p->upper));
        }
        seeds.push_back(std::move(e));
        started = true;
      }
    }
  }
  return seeds;
}

}  // namespace mcg::fit
