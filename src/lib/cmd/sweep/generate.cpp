// mcg-sweep's generators: the options they share, each one's own, and the table written.
#include "cmd/sweep/generate.hpp"

#include <limits>

#include "common/demand.hpp"
#include "signal/excitation.hpp"

namespace mcg::cmd {

using signal::Generator;
using signal::GeneratorOptions;

namespace {

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
  sub.add_option("--seed", o.seed, "random seed (prbs, aprbs, random multisine phases)")
      ->capture_default_str();
}

void add_band(CLI::App& sub, GeneratorOptions& o) {
  sub.add_option("--f0", o.f0_hz, "lowest frequency, Hz")
      ->check(CLI::Range(1e-6, 1e6))
      ->capture_default_str();
  sub.add_option("--f1", o.f1_hz, "highest frequency, Hz")
      ->check(CLI::Range(1e-6, 1e6))
      ->capture_default_str();
  sub.add_option("--spacing", o.spacing, "frequency spacing: linear or log")
      ->check(CLI::IsMember({"linear", "log"}));
}

void add_amp(CLI::App& sub, GeneratorOptions& o, const char* what) {
  sub.add_option("--amp", o.amp, what)->check(CLI::Range(0.0, 1e9))->capture_default_str();
}

void add_register(CLI::App& sub, GeneratorOptions& o) {
  sub.add_option("--order", o.order, "shift register length n (period 2^n - 1 bits)")
      ->check(CLI::Range(signal::k_prbs_min_order, signal::k_prbs_max_order))
      ->capture_default_str();
  sub.add_option("--clock", o.clock_s, "bit time, s, a whole number of --dt (default --dt)")
      ->check(CLI::Range(1e-6, 1e3));
}

}  // namespace

std::string SweepGenerate::name() const {
  switch (m_generator) {
    case Generator::step:
      return "step";
    case Generator::staircase:
      return "staircase";
    case Generator::chirp:
      return "chirp";
    case Generator::multisine:
      return "multisine";
    case Generator::prbs:
      return "prbs";
    case Generator::aprbs:
      return "aprbs";
  }
  MCG_DEMAND(!"a generator has a name");
  return {};
}

std::string SweepGenerate::help() const {
  switch (m_generator) {
    case Generator::step:
      return "a step, then further steps (--then)";
    case Generator::staircase:
      return "slow staircase 0 -> +amp -> -amp -> 0 (friction)";
    case Generator::chirp:
      return "swept sine from --f0 to --f1 over --duration";
    case Generator::multisine:
      return "periodic sum of sines at chosen lines";
    case Generator::prbs:
      return "maximal-length pseudo-random binary sequence, +-amp";
    case Generator::aprbs:
      return "amplitude-modulated PRBS, levels uniform in +-amp";
  }
  MCG_DEMAND(!"a generator has a help line");
  return {};
}

void SweepGenerate::define(CLI::App& app) {
  GeneratorOptions& o = options;
  add_common(app, o);
  switch (m_generator) {
    case Generator::step:
      app.add_option("--level", o.level, "level after --at (column's unit)")
          ->check(CLI::Range(-1e9, 1e9))
          ->capture_default_str();
      app.add_option("--at", o.at_s, "time of the step, s")
          ->check(CLI::Range(0.0, 1e6))
          ->capture_default_str();
      app.add_option("--then", o.then, "further steps level@time, e.g. 6@0.5,0@0.8");
      break;
    case Generator::staircase:
      add_amp(app, o, "largest level (column's unit)");
      app.add_option("--steps", o.steps, "levels on each side of zero")
          ->check(CLI::Range(1, 100000))
          ->capture_default_str();
      app.add_option("--hold", o.hold_s, "time on each level, s")
          ->check(CLI::Range(1e-6, 1e6))
          ->capture_default_str();
      break;
    case Generator::chirp:
      add_amp(app, o, "amplitude (column's unit)");
      add_band(app, o);
      app.add_option("--settle", o.settle_s, "bias alone before and after the sweep, s")
          ->check(CLI::Range(0.0, 1e6))
          ->capture_default_str();
      break;
    case Generator::multisine:
      add_amp(app, o, "peak of the sum (column's unit)");
      add_band(app, o);
      app.add_option("--lines", o.lines, "number of lines in the band")
          ->check(CLI::Range(1, 100000))
          ->capture_default_str();
      app.add_option("--period", o.period_s, "period, s, a whole number of --dt (default 1/f0)")
          ->check(CLI::Range(1e-6, 1e6));
      app.add_option("--phases", o.phases, "phases: schroeder, random (--seed) or zero")
          ->check(CLI::IsMember({"schroeder", "random", "zero"}))
          ->capture_default_str();
      break;
    case Generator::prbs:
      add_amp(app, o, "level (column's unit)");
      add_register(app, o);
      break;
    case Generator::aprbs:
      add_amp(app, o, "largest level (column's unit)");
      add_register(app, o);
      break;
  }
}

int SweepGenerate::run(Io& io) {
  options.tool = io.tool;
  signal::generate(m_generator, options, io.out);
  return 0;
}

}  // namespace mcg::cmd
