// mcg-fit: parameters from measured runs: friction, transfer function, grey-box model.
#include <CLI/CLI.hpp>
#include <iostream>

#include "common/range.hpp"
#include "common/tool.hpp"
#include "fit/gap.hpp"
#include "fit/run.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Identify the rig from measured runs: friction, a transfer function, the nonlinear model.",
               "mcg-fit"};
  app.require_subcommand(1);

  mcg::fit::FrictionRunOptions friction;
  CLI::App* fr =
      app.add_subcommand("friction", "static, Coulomb and viscous friction per clutch state, stacked");
  fr->add_option("--config", friction.config, "INI parameter set (R, Kt, Ke, J; repeatable, later files win)")
      ->allow_extra_args(false);
  fr->add_option("--order", friction.fit.order, "order of the viscous polynomial")
      ->check(mcg::Range(1, 3))
      ->capture_default_str();
  fr->add_option("--settle", friction.fit.settle_s, "time skipped after a jump of v, s")
      ->check(mcg::Range(0.0, 100.0))
      ->capture_default_str();
  fr->add_option("--jump", friction.fit.jump_V, "change of v between rows that counts as a jump, V")
      ->check(mcg::Range(0.0, 100.0))
      ->capture_default_str();
  fr->add_option("--window", friction.fit.window_s, "averaging window, s")
      ->check(mcg::Range(0.002, 100.0))
      ->capture_default_str();
  fr->add_flag("!--no-current", friction.fit.use_current,
               "ignore a measured current (use the voltage balance)");
  fr->add_flag("!--no-static", friction.fit.static_friction,
               "runs never rest: no static level (Ts written = Tc)");
  fr->add_option("--torque", friction.fit.torque_column,
                 "column holding the drive torque (N m; N with --linear) itself");
  fr->add_option("--position", friction.fit.position_column,
                 "column holding the position (rad; m with --linear): speed by differences");
  fr->add_flag("--fit-inertia", friction.fit.fit_inertia, "estimate the inertia (mass) with the friction");
  fr->add_flag("--offset", friction.fit.offset, "estimate a constant drive bias with the friction");
  fr->add_flag("--linear", friction.linear, "linear axis: m, N, N s/m, kg; results in [fit.friction] only");
  fr->add_option("files", friction.files, "runs with t, v, clutch, r_load, rpm [, i] ('-' = stdin)")
      ->required();

  mcg::fit::TfRunOptions tf;
  CLI::App* tfc = app.add_subcommand(
      "tf",
      "rational transfer function fitted to a frequency response or to a time-domain run (output error)");
  tfc->add_option("--poles", tf.fit.poles, "number of poles")
      ->check(mcg::Range(1, 12))
      ->capture_default_str();
  tfc->add_option("--zeros", tf.fit.zeros, "number of zeros")
      ->check(mcg::Range(0, 12))
      ->capture_default_str();
  tfc->add_option("--f-min,--fmin", tf.fit.f_min_hz, "ignore frequencies below, Hz")
      ->check(mcg::Range(0.0, 1e9));
  tfc->add_option("--f-max,--fmax", tf.fit.f_max_hz, "ignore frequencies above, Hz")
      ->check(mcg::Range(0.0, 1e9));
  tfc->add_flag("!--no-coherence", tf.fit.use_coherence, "weight all frequencies alike");
  tfc->add_flag("--delay", tf.fit.fit_delay, "fit a transport delay too (written as delay_s)");
  tfc->add_option(
      "--units", tf.units,
      "what the response maps when its metadata does not say: 'v -> rpm', 'duty -> rpm', 'v -> omega'");
  tfc->add_option("--in", tf.in_column, "time-domain run: the input column (v)");
  tfc->add_option("--out", tf.out_column, "time-domain run: the output column (rpm, else omega)");
  tfc->add_option("--validate", tf.validate, "time-domain run: a held-out run the fit is scored on");
  tfc->add_option(
         "file", tf.file,
         "f_hz,mag_db,phase_deg[,coherence] table, or a run with t and the two columns ('-' = stdin)")
      ->capture_default_str();

  mcg::fit::ModelRunOptions model;
  CLI::App* md = app.add_subcommand("model", "grey-box fit of the nonlinear model to time series");
  md->add_option("--config", model.config,
                 "INI parameter set: initial and fixed values (repeatable, later files win)")
      ->allow_extra_args(false);
  md->add_option(
        "--free", model.free,
        "parameters to fit, comma separated (default from the data: J, R, Kt, Ke, Tc with a current, "
        "else J, Kt = Ke, Tc)")
      ->allow_extra_args(false)
      ->delimiter(',');
  md->add_option("--fix", model.fix, "measured parameters pinned, NAME=VALUE, comma separated")
      ->allow_extra_args(false)
      ->delimiter(',');
  md->add_option("--tie", model.tie, "FOLLOWER=LEADER: the follower takes the leader's fitted value")
      ->allow_extra_args(false)
      ->delimiter(',');
  md->add_flag("--evaluate", model.evaluate, "no fit: fit % and RMS of the given model on the runs");
  md->add_option("--from", model.from_s, "use the rows of each run from this time on, s");
  md->add_option("--to", model.to_s, "use the rows of each run up to this time, s");
  md->add_option("--gear-ratio", model.gear_ratio,
                 "motor turns per turn of the shaft whose speed was measured")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  md->add_option("--outputs", model.outputs,
                 "measured columns compared (default: rpm and each varying i, i_gen, v_gen)")
      ->allow_extra_args(false)
      ->delimiter(',');
  md->add_flag("--batch", model.batch, "one fit per file, one CSV row each, files in parallel");
  md->add_flag("--list", model.list, "list the parameter names, values, units and bounds, then stop");
  md->add_option("--threads", model.threads, "worker threads (0 = every core)")
      ->check(mcg::Range(0, 1024))
      ->capture_default_str();
  md->add_option("--max-step", model.max_step_s, "integrator step bound during the fit, s")
      ->check(mcg::Range(1e-6, 1e-3))
      ->capture_default_str();
  md->add_option("--max-evaluations", model.max_evaluations, "simulation budget of the solver")
      ->check(mcg::Range(1, 1000000))
      ->capture_default_str();
  md->add_option("files", model.files, "measured runs ('-' = stdin)");

  mcg::fit::GapOptions gap;
  CLI::App* gp = app.add_subcommand(
      "gap", "where the model misses the runs, which effect explains it, how far it shrinks");
  gp->add_option("--config", gap.config, "INI parameter set of the model as given (later files win)");
  gp->add_option("--train", gap.train, "runs the candidates are fitted on ('-' = stdin)")->required();
  gp->add_option("--validate", gap.validate,
                 "held-out runs they are scored on (none: one --train file is split)");
  gp->add_option("--split", gap.split_fraction, "training share of a single file that is split")
      ->check(mcg::Range(0.2, 0.8))
      ->capture_default_str();
  gp->add_option("--format", gap.format, "csv (summary on stderr) or text")
      ->check(CLI::IsMember({"csv", "text"}))
      ->capture_default_str();
  gp->add_option("--residuals", gap.residuals, "write the validation residual series (CSV) to this file");
  gp->add_option("--fix", gap.fix, "measured parameters pinned, NAME=VALUE, comma separated (not rescaled)")
      ->allow_extra_args(false)
      ->delimiter(',');
  gp->add_option("--exclude", gap.exclude, "catalog effects not tried as candidates, comma separated")
      ->allow_extra_args(false)
      ->delimiter(',');
  gp->add_option("--from", gap.from_s, "use the rows of each run from this time on, s");
  gp->add_option("--to", gap.to_s, "use the rows of each run up to this time, s");
  gp->add_option("--gear-ratio", gap.gear_ratio, "motor turns per turn of the shaft whose speed was measured")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  gp->add_flag("--discrepancy", gap.discrepancy,
               "fit the catalog-free discrepancy terms whatever the verdict (always for an unexplained gap)");
  gp->add_option("--budget", gap.budget_s,
                 "wall-clock budget, s: after it the results so far, marked partial")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  gp->add_flag("--progress,!--no-progress", gap.progress,
               "progress lines on stderr (default: when it is a terminal)");
  gp->add_option("--threads", gap.threads, "candidates fitted at once (0 = every core)")
      ->check(mcg::Range(0, 1024))
      ->capture_default_str();

  gap.progress = mcg::stderr_is_terminal();
  return mcg::tool_main_status(app, argc, argv, [&]() -> int {
    if (gp->parsed()) {
      return mcg::fit::run_gap(gap, std::cout, std::cerr);
    }
    if (fr->parsed()) {
      mcg::fit::run_friction(friction, std::cout);
      return 0;
    }
    if (tfc->parsed()) {
      tf.band_given = tfc->count("--f-min") + tfc->count("--f-max") + tfc->count("--no-coherence") > 0;
      mcg::fit::run_tf(tf, std::cout, std::cerr);
      return 0;
    }
    return mcg::fit::run_model(model, std::cout, std::cerr);
  });
}
