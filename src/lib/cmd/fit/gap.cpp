// mcg-fit gap: the options of fit::run_gap on the command line.
#include "cmd/fit/gap.hpp"

#include "cmd/fit/model.hpp"
#include "common/range.hpp"
#include "common/tool.hpp"

namespace mcg::cmd {

void FitGap::define(CLI::App& app) {
  fit::GapOptions& gap = options;
  CLI::App* gp = &app;
  gp->add_option("--config", gap.config, "INI parameter set of the model as given (later files win)");
  gp->add_option("--train", gap.train, "runs the candidates are fitted on ('-' = stdin)")->required();
  gp->add_option("--validate", gap.validate,
                 "held-out runs they are scored on (none: one --train file is split)");
  m_split = gp->add_option("--split", gap.split_fraction, "training share of a single file that is split")
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
  gp->add_option("--gear-ratio", gap.gear_ratio,
                 "motor turns per turn of the shaft whose speed was measured (default: the captures' "
                 "gear_ratio, else the INI's [measurement], else 1)")
      ->check(mcg::Range(1e-6, 1e6));
  gp->add_flag("--linear", gap.linear,
               "omega is a linear axis' speed, m/s; the gear ratio is then the motor's rad per m of travel");
  gp->add_flag("--current", gap.drive.current,
               "current-driven drive: the i column is the current loop's command, A (not compared)");
  gp->add_option("--torque", gap.drive.torque_column,
                 "torque-driven drive: this column is the drive torque, N m at the measured shaft (N with "
                 "--linear, the gear ratio in rad/m)")
      ->excludes("--current");
  gp->add_option("--position", gap.position_column,
                 "column holding the position (rad; m with --linear): speed by central differences");
  gp->add_flag("--discrepancy", gap.discrepancy,
               "fit the catalog-free discrepancy terms whatever the verdict (always for an unexplained gap)");
  gp->add_option("--budget", gap.budget_s,
                 "wall-clock budget, s: after it the results so far, marked partial")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  gp->add_flag("--progress,!--no-progress", gap.progress,
               "progress lines on stderr (default: when it is a terminal)");
  gp->add_option("--threads", gap.threads, "threads of the one pool (0 = every core)")
      ->check(mcg::Range(0, 1024))
      ->capture_default_str();
  add_jacobian_option(gp, gap.sensitivities);
  gap.progress = stderr_is_terminal();
}

int FitGap::run(Io& io) {
  options.split_given = m_split != nullptr && m_split->count() > 0;
  options.tool = io.tool;
  Diagnostics gap(io.diag.stream(), io.diag.prefix() + " gap");
  const int status = fit::run_gap(options, io.out, gap);
  return status != 0 ? status : gap.status();
}

}  // namespace mcg::cmd
