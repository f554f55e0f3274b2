// mcg-design: exact controller design, discretisation and loop analysis, down to fixed point.
#include <iostream>
#include <limits>

#include "common/range.hpp"
#include "common/tool.hpp"
#include "design/run.hpp"

namespace {

constexpr double k_inf = std::numeric_limits<double>::infinity();

void add_plant_options(CLI::App* sub, mcg::design::Options& o) {
  sub->add_option("--config", o.configs, "INI: [plant], [loop], [controller], [design] (repeatable, later wins)")
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
  sub->add_option("--prewarp", o.prewarp_rad_s, "Tustin prewarp frequency, rad/s")->check(mcg::Range(1e-12, k_inf));
  sub->add_flag("--zoh", o.zoh, "sample the continuous plant through a zero-order hold at --dt");
  sub->add_flag("--loop", o.loop, "wrap the plant in the report's chain: PWM, H-bridge, encoder, counts per sample");
  sub->add_flag("--rig", o.rig, "plant: the rig model of --config (or built in) linearised at an operating point");
  sub->add_option("--clutch", o.clutch, "clutch state of --rig (2)")->check(CLI::IsMember({0, 1, 2}));
  sub->add_option("--speed-rpm", o.speed_rpm, "operating speed of --rig, rpm")->check(mcg::Range(1e-9, k_inf));
  sub->add_option("--r-load", o.r_load_ohm, "generator load of --rig, ohm (inf = open)")->check(mcg::Range(0.0, k_inf));
  sub->add_option("--pwm-full-counts", o.pwm_full_counts, "duty counts at 100 % (922)")->check(mcg::Range(1e-9, k_inf));
  sub->add_option("--pwm-logic-v", o.pwm_logic_v, "PWM output at 100 % duty, V (5)")->check(mcg::Range(1e-9, k_inf));
  sub->add_option("--hbridge-gain", o.hbridge_gain, "H-bridge gain, V/V (4)")->check(mcg::Range(1e-9, k_inf));
  sub->add_option("--counts-per-rev", o.counts_per_rev, "encoder counts per revolution (512)")
      ->check(mcg::Range(1e-9, k_inf));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Designs controllers exactly (P, PI, PID, lead, lag, root locus, robust tuning), discretises them,\n"
      "analyses loops (margins, Bode, Nyquist, root locus, step) and writes the fixed-point coefficients\n"
      "the firmware runs. Designs and numbers are INI, series are CSV. See man mcg-design.",
      "mcg-design"};
  app.require_subcommand(1);
  mcg::design::Options o;
  auto design_sub = [&](const char* name, const char* help) {
    CLI::App* sub = app.add_subcommand(name, help);
    add_plant_options(sub, o);
    return sub;
  };
  CLI::App* p = design_sub("p", "P controller for a phase margin");
  p->add_option("--pm", o.pm_deg, "phase margin, degrees")->check(mcg::Range(0.0, 180.0));
  CLI::App* pi = design_sub("pi", "PI controller for a phase margin with a chosen zero or crossover");
  pi->add_option("--pm", o.pm_deg, "phase margin, degrees")->check(mcg::Range(0.0, 180.0));
  pi->add_option("--zero", o.zero_rad_s, "PI zero Ki/Kp, rad/s")->check(mcg::Range(1e-12, k_inf));
  pi->add_option("--wc", o.wc_rad_s, "crossover frequency, rad/s")->check(mcg::Range(1e-12, k_inf));
  CLI::App* pid = design_sub("pid", "PID with a filtered derivative for a phase margin at a crossover");
  pid->add_option("--pm", o.pm_deg, "phase margin, degrees")->check(mcg::Range(0.0, 180.0));
  pid->add_option("--wc", o.wc_rad_s, "crossover frequency, rad/s")->check(mcg::Range(1e-12, k_inf));
  pid->add_option("--ti-td", o.ti_over_td, "Ti/Td")->check(mcg::Range(1e-6, 1e6))->capture_default_str();
  pid->add_option("--n", o.n, "derivative filter: pole at N/Td (--form filtered)")
      ->check(mcg::Range(1e-6, 1e6))
      ->capture_default_str();
  pid->add_option("--form", o.pid_form,
                  "filtered: C(s) with the derivative filter, discretised by --method; board: the board's PID, "
                  "designed in z (backward differences, no filter; needs --dt)")
      ->check(CLI::IsMember({"filtered", "board"}))
      ->capture_default_str();
  CLI::App* lead = design_sub("lead", "lead compensator for a phase margin at a crossover");
  lead->add_option("--pm", o.pm_deg, "phase margin, degrees")->check(mcg::Range(0.0, 180.0));
  lead->add_option("--wc", o.wc_rad_s, "crossover frequency, rad/s")->check(mcg::Range(1e-12, k_inf));
  CLI::App* lag = design_sub("lag", "lag compensator for a phase margin with a DC gain");
  lag->add_option("--pm", o.pm_deg, "phase margin, degrees")->check(mcg::Range(0.0, 180.0));
  lag->add_option("--k-dc", o.k_dc, "controller DC gain")->check(mcg::Range(1e-12, k_inf));
  lag->add_option("--ratio", o.ratio, "zero at wc/ratio")->check(mcg::Range(1.0, 1e6))->capture_default_str();
  CLI::App* rd = design_sub("rlocus-design", "gain that puts closed-loop poles on a damping line");
  rd->add_option("--zeta", o.zeta, "damping ratio, 0..1")->check(mcg::Range(0.0, 1.0));
  CLI::App* tune = design_sub("tune", "robust tuning: highest crossover within PM, GM and Ms limits");
  tune->add_option("--structure", o.structure, "p or pi")->check(CLI::IsMember({"p", "pi"}))->capture_default_str();
  tune->add_option("--pm-min", o.limits.pm_min_deg, "least phase margin, degrees")
      ->check(mcg::Range(0.0, 180.0))
      ->capture_default_str();
  tune->add_option("--gm-min", o.limits.gm_min_db, "least gain margin, dB")->check(mcg::Range(0.0, 200.0))->capture_default_str();
  tune->add_option("--ms-max", o.limits.ms_max, "largest peak sensitivity")->check(mcg::Range(1.0, 100.0))->capture_default_str();

  auto analysis_sub = [&](const char* name, const char* help) {
    CLI::App* sub = app.add_subcommand(name, help);
    add_plant_options(sub, o);
    sub->add_option("--controller", o.controller, "controller text in s or z (default: [controller] of --config, or 1)");
    return sub;
  };
  analysis_sub("margins", "all crossovers, gain/phase/delay margins, Ms, closed-loop poles, stable gains (INI)");
  for (const char* name : {"bode", "nyquist"}) {
    CLI::App* sub = analysis_sub(name, name[0] == 'b' ? "frequency response: f_hz, mag_db, phase_deg (CSV)"
                                                     : "Nyquist plot: f_hz, re, im (CSV)");
    sub->add_option("--f-min", o.f_min_hz, "lowest frequency, Hz")->check(mcg::Range(1e-12, k_inf));
    sub->add_option("--f-max", o.f_max_hz, "highest frequency, Hz")->check(mcg::Range(1e-12, k_inf));
    sub->add_option("--points", o.points, "number of frequencies (500)")->check(mcg::Range(2, 1000000));
  }
  CLI::App* rl = analysis_sub("rlocus", "root locus of 1 + K L: k, branch, re, im (CSV)");
  rl->add_option("--k-max", o.k_max, "largest gain")->check(mcg::Range(1e-12, k_inf));
  rl->add_option("--points", o.points, "number of gains (400)")->check(mcg::Range(2, 1000000));
  CLI::App* step = analysis_sub("step", "unit step, closed loop (t, r, y, e, u) or open (t, r, y, u): CSV with stepinfo metrics");
  step->add_flag("--open-loop", o.open_loop, "the step of the plant (times the controller) as typed, no feedback");
  step->add_option("--rise", o.rise_pct, "rise-time limits LOW,HIGH, % of the final value (10,90)");
  step->add_option("--settling", o.settling_pct, "settling band, % (2)")->check(mcg::Range(1e-9, 100.0));
  step->add_option("--t-end", o.t_end_s, "duration, s (10 time constants of the slowest pole)")
      ->check(mcg::Range(1e-12, k_inf));
  step->add_option("--points", o.points, "samples of a continuous loop (2000)")->check(mcg::Range(2, 1000000));
  step->add_flag("--metrics", o.metrics, "write the step metrics as INI instead of the series");
  CLI::App* c2d = app.add_subcommand("c2d", "discretise the plant: [plant] in z (INI)");
  add_plant_options(c2d, o);
  CLI::App* loop = app.add_subcommand("loop", "the report's Figure 17-1 chain: every gain, the ZOH loop, its margins (INI)");
  add_plant_options(loop, o);

  return mcg::tool_main(app, argc, argv, [&] {
    const CLI::App* sub = app.get_subcommands().front();
    o.command = sub->get_name();
    o.plant_given = sub->count("--plant") > 0;
    mcg::design::run(o, std::cout);
  });
}
