// mcg-sweep: excitation tables (step, staircase, chirp, multisine, prbs, aprbs) and the
// frequency response between two columns of a table (bode).
#include "common/tool.hpp"
#include "signal/excitation.hpp"
#include "signal/sweep.hpp"

#include <CLI/CLI.hpp>

#include <iostream>
#include <limits>
#include <map>

namespace {

using mcg::signal::Generator;
using mcg::signal::GeneratorOptions;

// Options every generator shares: column, bias, sampling, clutch and load, seed.
void add_common(CLI::App& sub, GeneratorOptions& o) {
  sub.add_option("--column", o.column, "column to excite")
      ->check(CLI::IsMember({"v", "duty", "rpm_cmd"}))
      ->capture_default_str();
  sub.add_option("--bias", o.bias, "constant added to the excitation (column's unit)")
      ->check(CLI::Range(-1e9, 1e9))
      ->capture_default_str();
  sub.add_option("--dt", o.dt_s, "sample period, s")->check(CLI::Range(1e-6, 10.0))->capture_default_str();
  sub.add_option("--duration", o.duration_s, "length of the table, s (default per generator)")
      ->check(CLI::Range(1e-6, 1e6));
  sub.add_option("--clutch", o.clutch, "clutch state held (0 alone, 1 attached, 2 engaged)")
      ->check(CLI::IsMember({0.0, 1.0, 2.0}))
      ->capture_default_str();
  sub.add_option("--clutch-schedule", o.clutch_schedule, "clutch changes state@time, e.g. 1@0,2@1.5");
  sub.add_option("--r-load", o.r_load_ohm, "generator load resistor held, ohm (inf = open)")
      ->check(CLI::Range(0.0, std::numeric_limits<double>::infinity()))
      ->capture_default_str();
  sub.add_option("--r-load-schedule", o.r_load_schedule, "load changes ohm@time, e.g. inf@0,5.6@2");
  sub.add_option("--seed", o.seed, "random seed (prbs, aprbs, random multisine phases)")->capture_default_str();
}

void add_band(CLI::App& sub, GeneratorOptions& o) {
  sub.add_option("--f0", o.f0_hz, "lowest frequency, Hz")->check(CLI::Range(1e-6, 1e6))->capture_default_str();
  sub.add_option("--f1", o.f1_hz, "highest frequency, Hz")->check(CLI::Range(1e-6, 1e6))->capture_default_str();
  sub.add_option("--spacing", o.spacing, "frequency spacing: linear or log")
      ->check(CLI::IsMember({"linear", "log"}));
}

void add_amp(CLI::App& sub, GeneratorOptions& o, const char* what) {
  sub.add_option("--amp", o.amp, what)->check(CLI::Range(0.0, 1e9))->capture_default_str();
}

void add_register(CLI::App& sub, GeneratorOptions& o) {
  sub.add_option("--order", o.order, "shift register length n (period 2^n - 1 bits)")
      ->check(CLI::Range(mcg::signal::k_prbs_min_order, mcg::signal::k_prbs_max_order))
      ->capture_default_str();
  sub.add_option("--clock", o.clock_s, "bit time, s, a whole number of --dt (default --dt)")
      ->check(CLI::Range(1e-6, 1e3));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Excitation tables for mcg-sim or the board, and frequency responses of measured tables.",
               "mcg-sweep"};
  app.require_subcommand(1);
  GeneratorOptions gen;
  std::map<CLI::App*, Generator> generators;

  CLI::App* step = app.add_subcommand("step", "a step, then further steps (--then)");
  add_common(*step, gen);
  step->add_option("--level", gen.level, "level after --at (column's unit)")
      ->check(CLI::Range(-1e9, 1e9))
      ->capture_default_str();
  step->add_option("--at", gen.at_s, "time of the step, s")->check(CLI::Range(0.0, 1e6))->capture_default_str();
  step->add_option("--then", gen.then, "further steps level@time, e.g. 6@0.5,0@0.8");
  generators[step] = Generator::step;

  CLI::App* staircase = app.add_subcommand("staircase", "slow staircase 0 -> +amp -> -amp -> 0 (friction)");
  add_common(*staircase, gen);
  add_amp(*staircase, gen, "largest level (column's unit)");
  staircase->add_option("--steps", gen.steps, "levels on each side of zero")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  staircase->add_option("--hold", gen.hold_s, "time on each level, s")
      ->check(CLI::Range(1e-6, 1e6))
      ->capture_default_str();
  generators[staircase] = Generator::staircase;

  CLI::App* chirp = app.add_subcommand("chirp", "swept sine from --f0 to --f1 over --duration");
  add_common(*chirp, gen);
  add_amp(*chirp, gen, "amplitude (column's unit)");
  add_band(*chirp, gen);
  chirp->add_option("--settle", gen.settle_s, "bias alone before and after the sweep, s")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  generators[chirp] = Generator::chirp;

  CLI::App* multisine = app.add_subcommand("multisine", "periodic sum of sines at chosen lines");
  add_common(*multisine, gen);
  add_amp(*multisine, gen, "peak of the sum (column's unit)");
  add_band(*multisine, gen);
  multisine->add_option("--lines", gen.lines, "number of lines in the band")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  multisine->add_option("--period", gen.period_s, "period, s, a whole number of --dt (default 1/f0)")
      ->check(CLI::Range(1e-6, 1e6));
  multisine->add_option("--phases", gen.phases, "phases: schroeder, random (--seed) or zero")
      ->check(CLI::IsMember({"schroeder", "random", "zero"}))
      ->capture_default_str();
  generators[multisine] = Generator::multisine;

  CLI::App* prbs = app.add_subcommand("prbs", "maximal-length pseudo-random binary sequence, +-amp");
  add_common(*prbs, gen);
  add_amp(*prbs, gen, "level (column's unit)");
  add_register(*prbs, gen);
  generators[prbs] = Generator::prbs;

  CLI::App* aprbs = app.add_subcommand("aprbs", "amplitude-modulated PRBS, levels uniform in +-amp");
  add_common(*aprbs, gen);
  add_amp(*aprbs, gen, "largest level (column's unit)");
  add_register(*aprbs, gen);
  generators[aprbs] = Generator::aprbs;

  mcg::signal::BodeOptions bode;
  CLI::App* bode_cmd = app.add_subcommand("bode", "frequency response f_hz,mag_db,phase_deg,coherence");
  bode_cmd->add_option("file", bode.input, "input table (- = stdin)")->capture_default_str();
  bode_cmd->add_option("--in", bode.in_column,
                       "input column (default: the excitation line's column, else v)");
  bode_cmd->add_option("--out", bode.out_column, "output column (default: omega, else rpm)");
  bode_cmd->add_option("--method", bode.method, "auto (lines when the table is a multisine), welch or lines")
      ->transform(CLI::CheckedTransformer(std::map<std::string, mcg::signal::BodeMethod>{
          {"auto", mcg::signal::BodeMethod::automatic},
          {"welch", mcg::signal::BodeMethod::welch},
          {"lines", mcg::signal::BodeMethod::lines}}));
  bode_cmd->add_option("--segment", bode.segment, "Welch segment, samples (default: a power of two near n/8)")
      ->check(CLI::Range(std::size_t{16}, std::size_t{1} << 24));
  bode_cmd->add_option("--overlap", bode.overlap, "Welch segment overlap, fraction")
      ->check(CLI::Range(0.0, 0.95))
      ->capture_default_str();
  bode_cmd->add_option("--lines", bode.lines_hz, "multisine lines, Hz, e.g. 1,2,5 (default from metadata)");
  bode_cmd->add_option("--period", bode.period_s, "multisine period, s (default from metadata)")
      ->check(CLI::Range(1e-6, 1e6));
  bode_cmd->add_option("--f-min,--fmin", bode.f_min_hz, "lowest frequency written, Hz (default: excitation band)")
      ->check(CLI::Range(0.0, 1e9));
  bode_cmd->add_option("--f-max,--fmax", bode.f_max_hz, "highest frequency written, Hz (default: excitation band)")
      ->check(CLI::Range(0.0, 1e9));

  return mcg::tool_main(app, argc, argv, [&] {
    if (bode_cmd->parsed()) {
      mcg::signal::bode(bode, std::cout, std::cerr);
      return;
    }
    for (const auto& [sub, generator] : generators) {
      if (sub->parsed()) mcg::signal::generate(generator, gen, std::cout);
    }
  });
}
