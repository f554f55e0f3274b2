// gnuplot script building for mcg-plot-gnuplot: data in inline blocks, every string quoted.
#pragma once

#include "table/table.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mcg::plot {

/// A gnuplot string expression holding `text`: control characters (newlines, carriage
/// returns, escapes, DEL) are dropped, the rest goes inside single quotes, and each ' is
/// spliced in as the double-quoted literal "'" ('it'."'".'s'). Single-quoted strings undergo
/// no backslash escapes, no macro (@) and no backquote (command) substitution, and "'" holds
/// nothing to substitute, so data can never become a command.
std::string quote(std::string_view text);

/// Axis label of a column with its unit from the data contract: "rpm (rev/min)", "t (s)";
/// f_hz, mag_db and phase_deg read "frequency (Hz)", "magnitude (dB)", "phase (deg)".
/// A column a report derives from one of these (mcg-fit gap's omega_before, rpm_res_after) takes
/// its unit. On a linear axis (a table whose metadata hold linear_axis, as mcg-fit gap --linear
/// writes) omega holds m/s and theta m. Unknown columns are labelled by name alone.
std::string label_for(std::string_view column, bool linear_axis = false);

/// rlocus: im against re of mcg-design rlocus, equal axes, each branch its own line, the
/// open-loop poles (k = 0) marked, the asymptotes and the stability boundary from its metadata.
enum class Mode { series, bode, xy, rlocus };

/// Where the plot goes.
struct Output {
  enum class Kind { none, png, svg, pdf, dumb, window };
  Kind kind = Kind::none;
  std::string path;          ///< file for png/svg/pdf
  std::string window_term;   ///< qt, wxt or x11 for Kind::window
  int width = 0;             ///< pixels (png, svg, pdf at 100 per inch) or characters (dumb)
  int height = 0;
};

/// Output kind from a file name's extension (.png, .svg, .pdf, any case); throws mcg::Error
/// "-o: unknown format 'x.gif' (use .png, .svg or .pdf)".
Output::Kind kind_from_path(std::string_view path);

/// What to draw.
struct Spec {
  Mode mode = Mode::series;
  std::string x = "t";
  std::vector<std::string> y;   ///< left axis; empty = every column but x and y2
  std::vector<std::string> y2;  ///< right axis
  bool steps = false;           ///< sample-and-hold look: value k holds until sample k+1
  bool logx = false;
  bool logy = false;
  std::optional<std::string> title;  ///< overrides the metadata's title
  Output output;
};

/// One input table with the name shown in legends when several are overlaid.
struct Input {
  table::Table table;
  std::string label;
};

/// The title: spec.title, else the first table's `title` metadata, else its `excitation`
/// metadata, else none.
std::optional<std::string> title_of(const Spec& spec, const std::vector<Input>& inputs);

/// The complete gnuplot script: terminal and output (when spec.output says so), one inline
/// data block per input ($data1, $data2, ...) holding only the columns drawn (a table with a
/// `branch` column, as a root locus, is written branch by branch with a blank line between, so
/// each branch is its own line), labels and
/// the plot commands. Inputs after the first are drawn dashed in the same colours.
/// Throws mcg::Error for a missing column (naming the table) or an empty selection.
std::string build_script(const Spec& spec, const std::vector<Input>& inputs);

}  // namespace mcg::plot
