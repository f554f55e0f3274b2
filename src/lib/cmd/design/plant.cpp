// The plant subcommands: the plant resolved, discretised or shown in its chain.
#include "cmd/design/plant.hpp"

#include <fmt/format.h>

#include <cmath>
#include <ostream>

#include "common/error.hpp"
#include "config/ini.hpp"
#include "linsys/c2d.hpp"

namespace mcg::cmd {

namespace {

using config::Ini;
using design::Tf;
using design::write_margins;
using Chain = boardunits::LoopChain;

void write_c2d(const design::PlantOptions& o, const design::ResolvedPlant& r, std::ostream& out) {
  if (r.raw.discrete()) fail("{}: the plant is already discrete", r.raw_where);
  if (!(r.dt_s > 0.0)) fail("--dt: required");
  const linsys::C2dMethod method =
      o.method.empty() ? linsys::C2dMethod::zoh : linsys::parse_method(o.method, "--method");
  const double prewarp = std::isnan(o.prewarp_rad_s) ? 0.0 : o.prewarp_rad_s;
  Tf g = r.raw;
  if (r.chain)
    g = linsys::scaled(g, r.chain_values.gain() * boardunits::omega_per_v_factor(r.units, r.chain_values));
  const Tf h = linsys::c2d(g, r.dt_s, method, prewarp, r.raw_where);
  Ini ini;
  ini.set("plant", "tf", linsys::tf_text(h),
          fmt::format("{} of {}", linsys::method_name(method), linsys::tf_text(g)));
  ini.set("plant", "domain", "z");
  ini.set("plant", "dt_s", r.dt_s);
  ini.set("plant", "num", linsys::list_text(linsys::trim(h.num)));
  ini.set("plant", "den", linsys::list_text(linsys::trim(h.den)));
  ini.set("plant", "method", linsys::method_name(method));
  if (prewarp > 0.0) ini.set("plant", "prewarp_rad_s", prewarp);
  ini.write(out);
}

void write_loop(const design::ResolvedPlant& r, std::ostream& out) {
  const Chain& c = r.chain_values;
  Ini ini;
  ini.set("loop", "pwm_full_counts", c.pwm_full_counts, "duty counts at 100 %");
  ini.set("loop", "pwm_logic_v", c.pwm_logic_v, "V at 100 % duty");
  ini.set("loop", "pwm_v_per_count", c.pwm_v_per_count(), "PWM gain, V per duty count (report: .00542)");
  ini.set("loop", "hbridge_gain", c.hbridge_gain, "V/V (report: 4 = 20 V / 5 V)");
  ini.set("loop", "counts_per_rev", c.counts_per_rev);
  ini.set("loop", "encoder_counts_per_rad", c.counts_per_rad(), "report: 81.5");
  ini.set("loop", "dt_s", c.dt_s, "software conversion: counts summed over one period");
  ini.set("loop", "chain_gain", c.gain(), "counts per sample per (rad/s) per duty count, without the plant");
  const double g0 = r.raw.dc_gain();
  ini.set("loop", "plant_dc_gain", g0, "rad/s per V");
  ini.set("loop", "forward_gain", c.pwm_v_per_count() * c.hbridge_gain * g0,
          "rad/s per duty count (report: 0.3589)");
  ini.set("loop", "feedback_gain", c.counts_per_rad() * c.dt_s,
          "counts per sample per rad/s (report: 81.5*.001)");
  ini.set("loop", "loop_dc_gain", c.gain() * g0, "report's third-order fit: 0.0146");
  Tf cont = linsys::scaled(r.raw, c.gain());
  ini.set("loop", "tf_s", linsys::tf_text(cont), "chain x plant, without the hold");
  const Tf& z = r.setup.plant;
  ini.set("loop", "tf_z", linsys::tf_text(z), "with the PWM as a zero-order hold");
  ini.set("loop", "num_z", linsys::list_text(linsys::trim(z.num)));
  ini.set("loop", "den_z", linsys::list_text(linsys::trim(z.den)));
  write_margins(ini, "margins", {z}, r.dt_s);
  ini.write(out);
}

}  // namespace

void C2d::define(CLI::App& app) { define_plant(app, options.plant); }

int C2d::run(Io& io) {
  const design::ResolvedPlant r = resolve(options.plant, false);
  write_c2d(options.plant, r, io.out);
  return 0;
}

void Loop::define(CLI::App& app) { define_plant(app, options.plant); }

int Loop::run(Io& io) {
  options.plant.loop = true;
  const design::ResolvedPlant r = resolve(options.plant, false);
  write_loop(r, io.out);
  return 0;
}

}  // namespace mcg::cmd
