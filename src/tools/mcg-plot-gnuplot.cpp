// mcg-plot-gnuplot: plots columns of mcg tables with gnuplot (PNG, SVG, PDF, text, window).
#include <CLI/CLI.hpp>

#include "common/tool.hpp"
#include "plot/gnuplot.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "Plots columns of mcg tables (stdin or files) with gnuplot; a second file or --overlay is drawn "
      "dashed for comparison.",
      "mcg-plot-gnuplot"};
  mcg::plot::Options o;
  app.add_option("files", o.files, "tables to plot (default stdin; later ones are overlaid)");
  app.add_option("--overlay", o.overlays, "table drawn dashed over the first (e.g. simulated over measured)")
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("-x,--x", o.x, "column on the horizontal axis")->capture_default_str();
  app.add_option("-y,--y", o.y, "columns on the left axis, e.g. rpm,rpm_cmd (default: all but x)")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("--y2", o.y2, "columns on the right axis, e.g. i")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  auto* bode =
      app.add_flag("--bode", o.bode, "magnitude and phase panels from f_hz,mag_db,phase_deg (log f)");
  auto* xy = app.add_flag("--xy", o.xy, "points of y against x (e.g. -x v -y i), in any order");
  auto* rlocus = app.add_flag(
      "--rlocus", o.rlocus,
      "root locus of mcg-design rlocus: im against re, a line per branch, poles, asymptotes, boundary");
  app.add_flag("--steps", o.steps, "draw samples as held until the next (zero-order hold)");
  app.add_flag("--logx", o.logx, "logarithmic horizontal axis");
  app.add_flag("--logy", o.logy, "logarithmic vertical axis");
  app.add_option("--title", o.title, "title (default: the table's title or excitation metadata)");
  app.add_option("-o,--output", o.output, "output file; format from the extension: .png, .svg, .pdf");
  app.add_option("--term", o.term, "terminal instead of a file: dumb (text on stdout)")
      ->check(CLI::IsMember({"dumb"}));
  app.add_option("--script", o.script,
                 "write the generated gnuplot script (data inline) to FILE; alone, "
                 "without -o or --term, only the script is written");
  app.add_option("--size", o.size, "width,height in pixels (characters for --term dumb)")
      ->delimiter(',')
      ->expected(2)
      ->check(CLI::Range(10, 20000));
  auto* live =
      app.add_flag("--live", o.live,
                   "redraw as rows arrive (stdin or one file): a scrolling window of the last --window of x, "
                   "in a window, as text redrawn in place (--term dumb), or a PNG rewritten (-o)");
  app.add_option("--window", o.window_s, "--live: the span of x shown, in its units (s for t)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--interval", o.interval_s, "--live: seconds between redraws")
      ->check(CLI::Range(0.01, 3600.0))
      ->capture_default_str();
  live->excludes(bode)->excludes(xy)->excludes(rlocus);
  bode->excludes(xy);
  rlocus->excludes(bode)->excludes(xy);
  return mcg::tool_main(app, argc, argv, [&] { mcg::plot::run(o); });
}
