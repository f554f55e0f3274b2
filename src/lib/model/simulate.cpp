// The outputs of an open-loop simulation (simulate() itself is plant.cpp's), and the checks
// on its inputs.
#include <cmath>

#include "common/error.hpp"
#include "common/units.hpp"
#include "config/ini.hpp"
#include "model/model.hpp"

namespace mcg::model {

void Outputs::resize(std::size_t rows) {
  for (auto* v : {&omega_rad_s, &rpm, &theta_rad, &omega_gen_rad_s, &i_A, &i_gen_A, &v_gen_V, &v_applied_V}) {
    v->assign(rows, 0.0);
  }
}

void Outputs::store(std::size_t row, const State& s) {
  omega_rad_s[row] = s.omega_rad_s;
  rpm[row] = rpm_from_rad_s(s.omega_rad_s);
  theta_rad[row] = s.theta_rad;
  omega_gen_rad_s[row] = s.omega_gen_rad_s;
  i_A[row] = s.i_A;
  i_gen_A[row] = s.i_gen_A;
  v_gen_V[row] = s.v_gen_V;
  v_applied_V[row] = s.v_applied_V;
}

void validate_inputs(const Inputs& in, std::string_view source, std::size_t first_line) {
  const std::size_t n = in.t_s.size();
  if (n == 0) fail("{}: no data rows", source);
  const auto not_finite = [](double x) {
    return std::isnan(x) ? "an unmeasured value (nan or empty) is not allowed here" : "an infinite value is not allowed here";
  };
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t line = first_line + k;
    if (!std::isfinite(in.t_s[k])) fail("{}:{}: column 't': {}", source, line, not_finite(in.t_s[k]));
    if (k > 0 && !(in.t_s[k] > in.t_s[k - 1])) {
      fail("{}:{}: column 't': {} does not increase (previous row: {})", source, line,
           config::format_number(in.t_s[k]), config::format_number(in.t_s[k - 1]));
    }
    if (!std::isfinite(in.v_V[k])) fail("{}:{}: column 'v': {}", source, line, not_finite(in.v_V[k]));
    if (!in.i_cmd_A.empty() && !std::isfinite(in.i_cmd_A[k])) {
      fail("{}:{}: column 'i' (the drive's current): {}", source, line, not_finite(in.i_cmd_A[k]));
    }
    if (!in.T_cmd_Nm.empty() && !std::isfinite(in.T_cmd_Nm[k])) {
      fail("{}:{}: the drive torque: {}", source, line, not_finite(in.T_cmd_Nm[k]));
    }
    const double c = in.clutch[k];
    if (!(c == 0.0 || c == 1.0 || c == 2.0)) {
      fail("{}:{}: column 'clutch': {} is not a clutch state (0, 1 or 2)", source, line, config::format_number(c));
    }
    if (std::isnan(in.r_load_ohm[k]) || in.r_load_ohm[k] < 0.0) {
      fail("{}:{}: column 'r_load': {} is not a load (>= 0 ohm, inf = open circuit)", source, line,
           config::format_number(in.r_load_ohm[k]));
    }
  }
}

}  // namespace mcg::model
