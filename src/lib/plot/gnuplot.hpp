// mcg-plot-gnuplot: reads tables, builds the script and streams it into gnuplot's stdin.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace mcg::plot {

/// The tool's options as the command line gives them.
struct Options {
  std::vector<std::string> files;  ///< tables; none = stdin; the second and later are overlaid
  std::vector<std::string> overlays;  ///< --overlay tables, drawn dashed
  std::string x = "t";
  std::vector<std::string> y;
  std::vector<std::string> y2;
  bool bode = false;
  bool xy = false;
  bool rlocus = false;  ///< --rlocus: a root locus of mcg-design rlocus
  bool steps = false;
  bool logx = false;
  bool logy = false;
  std::optional<std::string> title;
  std::string output;  ///< -o FILE: .png, .svg or .pdf
  std::string term;    ///< "dumb" for text on stdout
  std::string script;  ///< --script FILE: also (or, without -o/--term, only) write the script
  std::optional<std::vector<int>> size;  ///< width,height: pixels, or characters for dumb
  bool live = false;        ///< --live: redraw as rows arrive
  double window_s = 10.0;   ///< --window: the last this many units of x are shown
  double interval_s = 0.5;  ///< --interval: seconds between redraws (a PNG is rewritten as often)
};

/// The gnuplot to run: $MCG_GNUPLOT if set, else "gnuplot" on PATH.
std::string gnuplot_program();

/// Plots as the options say: reads every table, builds the script, writes it to --script
/// and/or pipes it to `gnuplot -d` (whose stdout is ours, for --term dumb). Without -o or
/// --term the plot goes to an interactive window, or fails with a clear message when this
/// gnuplot (gnuplot-nox) or this session (no DISPLAY) has none. Throws mcg::Error when
/// gnuplot is missing or fails.
///
/// With `live` the one input (a file or stdin) is read row by row as it arrives, on a thread
/// of its own, into a RingWindow of the last window_s of x; every interval_s, when rows have
/// arrived, one persistent gnuplot draws the window: into the window terminal, as text
/// redrawn in place (--term dumb: the frame replaces the previous one on a terminal), or into
/// the PNG, written to a temporary file and renamed over it, so a viewer never sees half a
/// frame. A slow gnuplot costs frames, never rows. At the end of the input the last frame is
/// drawn; a malformed row ends it with the reader's error.
void run(const Options& options);

}  // namespace mcg::plot
