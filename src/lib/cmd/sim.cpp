// mcg-sim: the options of the simulation, the catalog and the emulated board; their bodies.
#include "cmd/sim.hpp"

#include <iostream>
#include <limits>

#include "model/model.hpp"

namespace mcg::cmd {

void Sim::define(CLI::App& app) {
  m_app = &app;
  sim::RunOptions& opt = options;
  app.add_option("--config", opt.configs,
                 "INI parameter set: model, [effect.NAME], [controller] (repeatable)")
      ->check(CLI::ExistingFile);
  app.add_option("--effect", opt.effects, "add an effect of the catalog: NAME[:key=value,...] (repeatable)");
  app.add_option("--clutch", opt.clutch, "clutch state when the input has no 'clutch' column")
      ->check(CLI::IsMember({0, 1, 2}))
      ->capture_default_str();
  app.add_option("--r-load", opt.r_load_ohm,
                 "generator load, ohm, when the input has no 'r_load' column (inf = open)")
      ->check(CLI::Range(0.0, std::numeric_limits<double>::infinity()))
      ->capture_default_str();
  app.add_flag("--encoder", opt.encoder,
               "rpm as the board measures it (encoder counts over --window); true speed in rpm_true");
  app.add_option("--window", opt.window_s, "encoder count window, s")
      ->check(CLI::Range(1e-5, 10.0))
      ->capture_default_str();
  app.add_option("--counts-per-rev", opt.counts_per_rev, "encoder counts per revolution (512 lines x4)")
      ->check(CLI::Range(1.0, 1e7))
      ->capture_default_str();
  app.add_flag("--open-loop", opt.open_loop, "ignore an 'rpm_cmd' column and drive with v or duty");
  app.add_option("--loop", opt.loop,
                 "the closed loop's controller: board (the firmware's core on the board's registers) or "
                 "equation (the [controller] difference equation in double)")
      ->check(CLI::IsMember({"board", "equation"}))
      ->capture_default_str();
  app.add_option("--noise-i", opt.noise_i_A, "Gaussian noise on i, standard deviation in A")
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--noise-v-gen", opt.noise_v_gen_V, "Gaussian noise on v_gen, standard deviation in V")
      ->check(CLI::Range(0.0, 100.0));
  app.add_flag("--adc", opt.adc,
               "i through the board's 10-bit ADC (1 ohm shunt, 2.5 V offset: -2.5..2.495 A)");
  app.add_option("--seed", opt.seed, "seed of the measurement noise")->capture_default_str();
  app.add_option("--max-step", opt.max_step_s, "largest integration step, s")
      ->check(CLI::Range(1e-7, 1e-3))
      ->capture_default_str();
  app.add_flag(
      "--compare", opt.compare,
      "the input is a measured run: keep its rpm and i as rpm_measured, i_measured, add the residuals "
      "and their running RMS per regime; the RMS per regime on stderr at the end");
  app.add_flag("--list-effects", list_effects,
               "instead: print the effect catalog (effect, parameter, unit, default, range, meaning)");
  app.add_option("--board", board.link_path,
                 "instead: serve the emulated board (firmware core + this model) on a pty linked at PATH");
  app.add_option("--speed", board.speed, "with --board: simulated seconds per wall-clock second")
      ->check(CLI::Range(0.01, 100.0))
      ->capture_default_str();
}

int Sim::run(Io& io) {
  if (list_effects) {
    model::write_effect_catalog(io.out);
    return 0;
  }
  if (!board.link_path.empty()) {
    board.configs = options.configs;
    board.effects = options.effects;
    for (const CLI::Option* o : m_app->get_options()) {
      if (o->count() > 0) board.options_given.push_back(o->get_name());
    }
    board.board.max_step_s = options.max_step_s;
    if (m_app->count("--r-load") > 0) board.board.r_load_ohm = options.r_load_ohm;
    board::serve(board, io.diag);
    return 0;
  }
  options.tool = io.tool;
  sim::run_stdio(options, io.diag);
  return 0;
}

}  // namespace mcg::cmd
