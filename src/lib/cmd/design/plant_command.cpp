// The plant and chain options of every mcg-design subcommand.
#include "cmd/design/plant_command.hpp"

#include <limits>

#include "common/range.hpp"

namespace mcg::cmd {

void PlantCommand::define_plant(CLI::App& app, design::PlantOptions& o) {
  constexpr double k_inf = std::numeric_limits<double>::infinity();
  m_app = &app;
  CLI::App* sub = &app;
  sub->add_option("--config", o.configs,
                  "INI: [plant], [loop], [controller], [design] (repeatable, later wins)")
      ->check(CLI::ExistingFile);
  sub->add_option("--plant", o.plant, "plant as text in s or z, e.g. '16.557/((s/65+1)*(s/950+1))'");
  sub->add_option("--num", o.num, "plant numerator coefficients, descending powers ('1 2' or '1,2')");
  sub->add_option("--den", o.den, "plant denominator coefficients, descending powers");
  sub->add_option(
      "--plant-units", o.plant_units,
      "what --plant maps: rpm/V, rad/s/V, rpm/duty, rad/s/duty (the loop chain is applied) or loop");
  sub->add_option("--domain", o.domain, "variable of --num/--den")->check(CLI::IsMember({"s", "z"}));
  sub->add_option("--delay", o.delay_s, "extra plant delay, s")->check(mcg::Range(0.0, k_inf));
  sub->add_option("--dt", o.dt_s, "sample period of the controller (and of a z plant), s")
      ->check(mcg::Range(1e-9, 1e6));
  sub->add_option("--method", o.method, "controller discretisation (tustin); for c2d the plant's (zoh)")
      ->check(CLI::IsMember({"zoh", "foh", "tustin", "matched", "impulse"}));
  sub->add_option("--prewarp", o.prewarp_rad_s, "Tustin prewarp frequency, rad/s")
      ->check(mcg::Range(1e-12, k_inf));
  sub->add_flag("--zoh", o.zoh, "sample the continuous plant through a zero-order hold at --dt");
  sub->add_flag("--loop", o.loop,
                "wrap the plant in the report's chain: PWM, H-bridge, encoder, counts per sample");
  sub->add_flag("--rig", o.rig,
                "plant: the rig model of --config (or built in) linearised at an operating point");
  sub->add_option("--clutch", o.clutch, "clutch state of --rig (2)")->check(CLI::IsMember({0, 1, 2}));
  sub->add_option("--speed-rpm", o.speed_rpm, "operating speed of --rig, rpm")
      ->check(mcg::Range(1e-9, k_inf));
  sub->add_option("--r-load", o.r_load_ohm, "generator load of --rig, ohm (inf = open)")
      ->check(mcg::Range(0.0, k_inf));
  sub->add_option("--pwm-full-counts", o.pwm_full_counts, "duty counts at 100 % (922)")
      ->check(mcg::Range(1e-9, k_inf));
  sub->add_option("--pwm-logic-v", o.pwm_logic_v, "PWM output at 100 % duty, V (5)")
      ->check(mcg::Range(1e-9, k_inf));
  sub->add_option("--hbridge-gain", o.hbridge_gain, "H-bridge gain, V/V (4)")->check(mcg::Range(1e-9, k_inf));
  sub->add_option("--counts-per-rev", o.counts_per_rev, "encoder counts per revolution (512)")
      ->check(mcg::Range(1e-9, k_inf));
}

design::ResolvedPlant PlantCommand::resolve(design::PlantOptions& plant, bool designs) const {
  plant.plant_given = m_app != nullptr && m_app->count("--plant") > 0;
  return design::resolve(plant, designs);
}

}  // namespace mcg::cmd
