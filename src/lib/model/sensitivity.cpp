// Forward-mode sensitivities: the compiled model lifted to dual numbers, simulated once per
// k_dual_dirs directions.
#include "model/sensitivity.hpp"

#include <algorithm>
#include <cmath>

#include "common/demand.hpp"
#include "common/units.hpp"
#include "model/effects/compiled.hpp"

namespace mcg::model {

namespace {

/// The compiled numbers at the base model and moved along up to k_dual_dirs directions.
struct Lifter {
  const Compiled& base;
  std::vector<Compiled> plus, minus;
  std::vector<double> two_steps;

  /// The number get(c) with its central differences along each direction.
  template <class Get>
  Dual operator()(Get get) const {
    Dual x(get(base));
    for (std::size_t j = 0; j < plus.size(); ++j) x.d[j] = (get(plus[j]) - get(minus[j])) / two_steps[j];
    return x;
  }
  template <class Get>
  std::array<Dual, 4> array4(Get get) const {
    std::array<Dual, 4> out;
    for (std::size_t m = 0; m < 4; ++m) out[m] = (*this)([&](const Compiled& c) { return get(c)[m]; });
    return out;
  }
  template <class Get>
  BasicFriction<Dual> friction(Get get) const {
    BasicFriction<Dual> f;
    f.Ts_Nm = (*this)([&](const Compiled& c) { return get(c).Ts_Nm; });
    f.Tc_Nm = (*this)([&](const Compiled& c) { return get(c).Tc_Nm; });
    for (std::size_t m = 0; m < 3; ++m)
      f.viscous[m] = (*this)([&](const Compiled& c) { return get(c).viscous[m]; });
    return f;
  }
  template <class Get>
  BasicMachine<Dual> machine(Get get) const {
    BasicMachine<Dual> out;
    out.R_ohm = (*this)([&](const Compiled& c) { return get(c).R_ohm; });
    out.L_H = (*this)([&](const Compiled& c) { return get(c).L_H; });
    out.Kt_Nm_A = (*this)([&](const Compiled& c) { return get(c).Kt_Nm_A; });
    out.Ke_V_s_rad = (*this)([&](const Compiled& c) { return get(c).Ke_V_s_rad; });
    out.J_kg_m2 = (*this)([&](const Compiled& c) { return get(c).J_kg_m2; });
    out.friction = friction([&](const Compiled& c) -> const Friction& { return get(c).friction; });
    return out;
  }

  /// Every moved model has the base's hooks: the same terms, functions and switches.
  bool same_structure() const {
    const auto same = [&](const Compiled& c) {
      if (c.friction_terms.size() != base.friction_terms.size() ||
          c.motor_torque.size() != base.motor_torque.size())
        return false;
      for (std::size_t k = 0; k < c.friction_terms.size(); ++k) {
        const FrictionTerm &a = c.friction_terms[k], &b = base.friction_terms[k];
        if (a.fn != b.fn || a.breakaway != b.breakaway) return false;
      }
      for (std::size_t k = 0; k < c.motor_torque.size(); ++k) {
        const TorqueTerm &a = c.motor_torque[k], &b = base.motor_torque[k];
        if (a.fn != b.fn || a.fn_it != b.fn_it) return false;
      }
      return c.winding.rate == base.winding.rate && c.coupling.capacity == base.coupling.capacity &&
             c.friction_needs_load == base.friction_needs_load;
    };
    return std::all_of(plus.begin(), plus.end(), same) && std::all_of(minus.begin(), minus.end(), same);
  }

  /// Every hook the base has in its dual form too.
  bool has_dual_hooks() const {
    for (const FrictionTerm& t : base.friction_terms) {
      if (t.fn_dual == nullptr || (t.breakaway != nullptr && t.breakaway_dual == nullptr)) return false;
    }
    for (const TorqueTerm& t : base.motor_torque) {
      if ((t.fn != nullptr && t.fn_dual == nullptr) || (t.fn_it != nullptr && t.fn_it_dual == nullptr))
        return false;
    }
    return (base.winding.rate == nullptr || base.winding.rate_dual != nullptr) &&
           (base.coupling.capacity == nullptr || base.coupling.capacity_dual != nullptr);
  }

  CompiledDual lift() const {
    CompiledDual out;
#define MCG_LIFT(field) out.field = (*this)([](const Compiled& c) { return c.field; })
    out.p.motor = machine([](const Compiled& c) -> const Machine& { return c.p.motor; });
    out.p.generator = machine([](const Compiled& c) -> const Machine& { return c.p.generator; });
    out.p.clutch_disengaged =
        friction([](const Compiled& c) -> const Friction& { return c.p.clutch_disengaged; });
    out.p.clutch_engaged = friction([](const Compiled& c) -> const Friction& { return c.p.clutch_engaged; });
    MCG_LIFT(p.supply_V);
    MCG_LIFT(p.dead_time_s);
    MCG_LIFT(delay_s);
    MCG_LIFT(circuit.R_series_ohm);
    MCG_LIFT(circuit.R_duty_ohm);
    MCG_LIFT(circuit.deadband);
    MCG_LIFT(circuit.V_sat_V);
    MCG_LIFT(circuit.i_sat_A);
    MCG_LIFT(circuit.coast);
    out.winding.rate = base.winding.rate_dual;
    out.winding.k = array4([](const Compiled& c) { return c.winding.k; });
    MCG_LIFT(winding.R_per_x);
    MCG_LIFT(winding.x0);
    MCG_LIFT(coupling.spring_k_Nm_rad);
    MCG_LIFT(coupling.zeta);
    out.coupling.capacity = base.coupling.capacity_dual;
    out.coupling.capacity_k = array4([](const Compiled& c) { return c.coupling.capacity_k; });
    for (std::size_t k = 0; k < base.friction_terms.size(); ++k) {
      BasicFrictionTerm<Dual> t;
      t.fn = base.friction_terms[k].fn_dual;
      t.breakaway = base.friction_terms[k].breakaway_dual;
      t.k = array4([k](const Compiled& c) { return c.friction_terms[k].k; });
      out.friction_terms.push_back(t);
    }
    for (std::size_t k = 0; k < base.motor_torque.size(); ++k) {
      BasicTorqueTerm<Dual> t;
      t.fn = base.motor_torque[k].fn_dual;
      t.fn_it = base.motor_torque[k].fn_it_dual;
      t.k = array4([k](const Compiled& c) { return c.motor_torque[k].k; });
      t.angle_rate = base.motor_torque[k].angle_rate;
      out.motor_torque.push_back(t);
    }
    for (std::size_t m = 0; m < 3; ++m)
      out.motor_side[m] = friction([m](const Compiled& c) -> const Friction& { return c.motor_side[m]; });
    out.rigid = friction([](const Compiled& c) -> const Friction& { return c.rigid; });
    out.gen = friction([](const Compiled& c) -> const Friction& { return c.gen; });
    MCG_LIFT(J_total);
    MCG_LIFT(c_spring);
#undef MCG_LIFT
    out.friction_needs_load = base.friction_needs_load;
    return out;
  }
};

/// A row's dual state as a state of one part of each number: part(x) its value, or its
/// derivative along one direction.
template <class Part>
State project(const BasicState<Dual>& s, Part part) {
  State out;
  out.t_s = s.t_s;
  out.omega_rad_s = part(s.omega_rad_s);
  out.omega_gen_rad_s = part(s.omega_gen_rad_s);
  out.theta_rad = part(s.theta_rad);
  out.theta_gen_rad = part(s.theta_gen_rad);
  out.i_A = part(s.i_A);
  out.i_gen_A = part(s.i_gen_A);
  out.v_gen_V = part(s.v_gen_V);
  out.v_applied_V = part(s.v_applied_V);
  out.temp_rise_K = part(s.temp_rise_K);
  out.clutch = s.clutch;
  out.stuck = s.stuck;
  return out;
}

}  // namespace

std::vector<Direction> parameter_directions(const Model& model, const std::vector<std::string>& names) {
  std::vector<Direction> out;
  for (const std::string& name : names) {
    const double v = get_parameter(model, name);
    Direction d{model, model, v != 0.0 ? 1e-6 * std::abs(v) : 1e-9};
    set_parameter(d.plus, name, v + d.step);
    set_parameter(d.minus, name, v - d.step);
    out.push_back(std::move(d));
  }
  return out;
}

std::optional<Sensitivities> simulate_sensitivities(const Model& model,
                                                    const std::vector<Direction>& directions,
                                                    const Inputs& inputs, const SimOptions& options) {
  const Compiled base(model);
  const std::size_t n = inputs.t_s.size();
  Sensitivities out;
  out.value.resize(n);
  out.d.resize(directions.size());
  for (Outputs& d : out.d) d.resize(n);
  for (std::size_t first = 0; first < directions.size() || first == 0; first += k_dual_dirs) {
    const std::size_t count = std::min(k_dual_dirs, directions.size() - first);
    Lifter lifter{base, {}, {}, {}};
    Dual kt_cmd(model.params.motor.Kt_Nm_A);
    for (std::size_t j = 0; j < count; ++j) {
      const Direction& dir = directions[first + j];
      MCG_DEMAND(dir.step > 0.0);
      lifter.plus.emplace_back(dir.plus);
      lifter.minus.emplace_back(dir.minus);
      lifter.two_steps.push_back(2.0 * dir.step);
      kt_cmd.d[j] = (dir.plus.params.motor.Kt_Nm_A - dir.minus.params.motor.Kt_Nm_A) / (2.0 * dir.step);
    }
    if (!lifter.has_dual_hooks() || !lifter.same_structure()) return std::nullopt;
    simulate_states(lifter.lift(), kt_cmd, inputs, options,
                    [&](std::size_t k, const BasicState<Dual>& state) {
                      if (first == 0) out.value.store(k, project(state, [](const Dual& x) { return x.v; }));
                      for (std::size_t j = 0; j < count; ++j)
                        out.d[first + j].store(k, project(state, [j](const Dual& x) { return x.d[j]; }));
                    });
    if (directions.empty()) break;
  }
  return out;
}

}  // namespace mcg::model
