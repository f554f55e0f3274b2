// gnuplot scripts: terminal, inline data blocks, labels with units, plot commands.
#include "plot/script.hpp"

#include "common/error.hpp"
#include "config/ini.hpp"  // format_number

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>
#include <string_view>
#include <utility>

namespace mcg::plot {

namespace {

// Units of the data contract's columns (man/mcg-csv.5).
constexpr std::array<std::pair<std::string_view, std::string_view>, 20> k_labels = {{
    {"t", "t (s)"},
    {"v", "v (V)"},
    {"duty", "duty (1)"},
    {"clutch", "clutch (state)"},
    {"r_load", "r_load (ohm)"},
    {"rpm", "rpm (rev/min)"},
    {"omega", "omega (rad/s)"},
    {"i", "i (A)"},
    {"i_gen", "i_gen (A)"},
    {"v_gen", "v_gen (V)"},
    {"rpm_cmd", "rpm_cmd (rev/min)"},
    {"rpm_true", "rpm_true (rev/min)"},
    {"theta", "theta (rad)"},
    {"v_applied", "v_applied (V)"},
    {"counts", "counts (counts)"},
    {"f_hz", "frequency (Hz)"},
    {"mag_db", "magnitude (dB)"},
    {"phase_deg", "phase (deg)"},
    {"coherence", "coherence (1)"},
    {"y", "y"},
}};

void append_number(std::string& out, double v) {
  if (!std::isfinite(v)) {
    out += "NaN";
    return;
  }
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, v);
  out.append(text, result.ptr);
}

std::vector<std::string> joined_names(const std::vector<std::string>& a, const std::vector<std::string>& b) {
  std::vector<std::string> all = a;
  all.insert(all.end(), b.begin(), b.end());
  return all;
}

// The columns drawn from each table, x first.
struct Selection {
  std::string x;
  std::vector<std::string> y;
  std::vector<std::string> y2;
};

Selection select(const Spec& spec, const table::Table& first) {
  Selection s;
  if (spec.mode == Mode::bode) {
    s.x = "f_hz";
    s.y = {"mag_db", "phase_deg"};
    return s;
  }
  if (spec.mode == Mode::rlocus) {
    s.x = "re";
    s.y = {"im"};
    return s;
  }
  s.x = spec.x;
  s.y2 = spec.y2;
  s.y = spec.y;
  if (s.y.empty()) {
    // Every other column, but one that has nothing to draw (an unloaded generator's r_load,
    // inf throughout): a column named with -y that has none is an error.
    for (const std::string& name : first.names) {
      const auto& values = first.col(name);
      const bool drawable =
          std::any_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
      if (name != s.x && drawable && std::find(s.y2.begin(), s.y2.end(), name) == s.y2.end())
        s.y.push_back(name);
    }
  }
  if (s.y.empty() && s.y2.empty()) fail("{}: no column to plot besides {}", first.source, quote(s.x));
  return s;
}

void append_block(std::string& out, std::size_t index, const table::Table& tbl, const Selection& s) {
  std::vector<const std::vector<double>*> columns{&tbl.col(s.x)};
  for (const std::string& name : joined_names(s.y, s.y2)) columns.push_back(&tbl.col(name));
  for (std::size_t c = 0; c < columns.size(); ++c) {
    const auto& values = *columns[c];
    if (std::none_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); })) {
      fail("{}: column {} has no finite value to plot", tbl.source, quote(c == 0 ? s.x : joined_names(s.y, s.y2)[c - 1]));
    }
  }
  // Rows grouped by branch (in their order within it), a blank line where a branch ends.
  std::vector<std::size_t> order(tbl.rows());
  for (std::size_t r = 0; r < order.size(); ++r) order[r] = r;
  const std::vector<double>* branch = nullptr;
  const auto names = joined_names(s.y, s.y2);
  if (tbl.has("branch") && s.x != "branch" && std::find(names.begin(), names.end(), "branch") == names.end()) {
    branch = &tbl.col("branch");
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return (*branch)[a] < (*branch)[b]; });
  }
  out += fmt::format("$data{} << EOD\n", index);
  for (std::size_t i = 0; i < order.size(); ++i) {
    const std::size_t r = order[i];
    if (branch != nullptr && i > 0 && (*branch)[r] != (*branch)[order[i - 1]]) out += '\n';
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (c > 0) out += ' ';
      append_number(out, (*columns[c])[r]);
    }
    out += '\n';
  }
  out += "EOD\n";
}

/// Numbers of a metadata value ("60 180 300"); empty when absent or not numbers.
std::vector<double> meta_numbers(const table::Table& tbl, std::string_view key) {
  std::vector<double> out;
  const auto text = tbl.meta.get(key);
  if (!text) return out;
  const char* p = text->data();
  const char* end = p + text->size();
  while (p < end) {
    while (p < end && (*p == ' ' || *p == ',')) ++p;
    if (p >= end) break;
    double v = 0.0;
    const auto [next, ec] = std::from_chars(p, end, v);
    if (ec != std::errc() || next == p) return {};
    out.push_back(v);
    p = next;
  }
  return out;
}

/// The extras of a root locus: open-loop poles (rows with k = 0) as crosses, the asymptotes
/// (rays from `asymptote_centre` at `asymptote_angles_deg`, as long as the locus is wide) and
/// the stability boundary (`boundary`: unit circle or imaginary axis).
std::string rlocus_extras(const table::Table& tbl, std::string& plot) {
  std::string out;
  const auto& re = tbl.col("re");
  const auto& im = tbl.col("im");
  double reach = 0.0;
  if (tbl.has("k")) {
    const auto& k = tbl.col("k");
    out += "$poles << EOD\n";
    for (std::size_t r = 0; r < tbl.rows(); ++r) {
      if (k[r] != 0.0) continue;
      append_number(out, re[r]);
      out += ' ';
      append_number(out, im[r]);
      out += '\n';
    }
    out += "EOD\n";
    plot += ", \\\n     $poles using 1:2 with points pointtype 2 pointsize 2 linecolor rgb 'black' title 'open-loop poles'";
  }
  const std::vector<double> centre = meta_numbers(tbl, "asymptote_centre");
  const std::vector<double> angles = meta_numbers(tbl, "asymptote_angles_deg");
  if (centre.size() == 1 && !angles.empty()) {
    for (std::size_t r = 0; r < tbl.rows(); ++r) {
      if (std::isfinite(re[r]) && std::isfinite(im[r])) reach = std::max(reach, std::hypot(re[r] - centre[0], im[r]));
    }
    if (reach == 0.0) reach = 1.0;
    out += "$asymptotes << EOD\n";
    for (double a : angles) {
      const double rad = a * std::acos(-1.0) / 180.0;
      append_number(out, centre[0]);
      out += " 0\n";
      append_number(out, centre[0] + reach * std::cos(rad));
      out += ' ';
      append_number(out, reach * std::sin(rad));
      out += "\n\n";
    }
    out += "EOD\n";
    plot += ", \\\n     $asymptotes using 1:2 with lines dashtype 3 linecolor rgb 'gray40' title 'asymptotes'";
  }
  const auto boundary = tbl.meta.get("boundary");
  if (boundary && *boundary == "unit circle") {
    out += "set object 1 circle at 0,0 size 1 fillstyle empty border linecolor rgb 'gray40' dashtype 2 back\n";
    out += "set xrange [*<-1.1:1.1<*]\nset yrange [*<-1.1:1.1<*]\n";
  } else if (boundary && *boundary == "imaginary axis") {
    out += "set yzeroaxis linetype -1 linecolor rgb 'gray40' dashtype 2\n";
  }
  return out;
}

std::string join_labels(const std::vector<std::string>& names, bool linear_axis) {
  std::string text;
  for (const std::string& name : names) {
    if (!text.empty()) text += ", ";
    text += label_for(name, linear_axis);
  }
  return text;
}

std::string terminal_lines(const Output& o) {
  switch (o.kind) {
    case Output::Kind::png:
      return fmt::format("set terminal pngcairo size {},{} noenhanced font 'sans,10'\nset output {}\n", o.width,
                         o.height, quote(o.path));
    case Output::Kind::svg:
      return fmt::format("set terminal svg size {},{} noenhanced font 'sans,10' background '#ffffff'\nset output {}\n",
                         o.width, o.height, quote(o.path));
    case Output::Kind::pdf:
      return fmt::format("set terminal pdfcairo size {}in,{}in noenhanced font 'sans,10'\nset output {}\n",
                         o.width / 100.0, o.height / 100.0, quote(o.path));
    case Output::Kind::dumb:
      return fmt::format("set terminal dumb size {},{} noenhanced\n", o.width, o.height);
    case Output::Kind::window:
      return fmt::format("set terminal {} size {},{} noenhanced\n", o.window_term, o.width, o.height);
    case Output::Kind::none:
      break;
  }
  return "set termoption noenhanced\n";
}

std::string style_of(const Spec& spec) {
  if (spec.mode == Mode::xy) return "points pointtype 7 pointsize 0.5";
  return spec.steps ? "steps" : "lines";
}

std::string dashes(std::size_t block) { return block > 1 ? fmt::format(" dashtype {}", block) : ""; }

// Legend entry of column `name` from input `index` (file label only when overlaying).
std::string legend(const std::string& name, const std::vector<Input>& inputs, std::size_t index) {
  if (inputs.size() == 1) return quote(name);
  return quote(fmt::format("{} ({})", name, inputs[index].label));
}

// Curve of data block `block` (1 = the first table, solid; each overlay its own dash pattern).
std::string curve(std::size_t block, std::size_t column, std::size_t color, bool y2, const std::string& style,
                  const std::string& title) {
  return fmt::format("$data{} using 1:{}{} with {} linecolor {}{} title {}", block, column,
                     y2 ? " axes x1y2" : "", style, color, dashes(block), title);
}

/// "set yrange [...]" for an axis whose columns hold one value only (a live window of a shaft at
/// rest): the range gnuplot would widen it to (+-1 % of the value, +-1 at 0), set here so that
/// it does not warn on every frame. Empty for an axis with any spread.
std::string flat_range(std::string_view axis, const std::vector<std::string>& columns, const std::vector<Input>& inputs) {
  std::optional<double> value;
  for (const Input& in : inputs) {
    for (const std::string& name : columns) {
      const auto c = in.table.find(name);
      if (!c) continue;
      for (double v : in.table.columns[*c]) {
        if (!std::isfinite(v)) continue;
        if (value && v != *value) return {};
        value = v;
      }
    }
  }
  if (!value) return {};
  const double half = *value == 0.0 ? 1.0 : 0.01 * std::abs(*value);
  return fmt::format("set {} [{}:{}]\n", axis, config::format_number(*value - half), config::format_number(*value + half));
}

}  // namespace

std::string quote(std::string_view text) {
  std::string out = "'";
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) continue;
    // gnuplot reads '' as an escaped quote inside a string but as an empty string at its
    // start, so each quote is spliced in as a separate double-quoted literal instead.
    if (c == '\'') {
      out += R"('."'".')";
    } else {
      out += c;
    }
  }
  out += '\'';
  return out;
}

std::string label_for(std::string_view column, bool linear_axis) {
  if (linear_axis && column == "omega") return "omega (m/s)";
  if (linear_axis && column == "theta") return "theta (m)";
  for (const auto& [name, label] : k_labels) {
    if (name == column) return std::string(label);
  }
  // A report's columns on a contract column: its measurement, simulations and residuals.
  for (std::string_view suffix : {"_res_before", "_res_after", "_before", "_after"}) {
    if (column.size() <= suffix.size() || column.substr(column.size() - suffix.size()) != suffix) continue;
    const std::string base = label_for(column.substr(0, column.size() - suffix.size()), linear_axis);
    const std::size_t unit = base.rfind(" (");
    if (unit == std::string::npos) break;
    return std::string(column) + base.substr(unit);
  }
  return std::string(column);
}

Output::Kind kind_from_path(std::string_view path) {
  const std::size_t dot = path.rfind('.');
  std::string ext = dot == std::string_view::npos ? std::string() : std::string(path.substr(dot + 1));
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == "png") return Output::Kind::png;
  if (ext == "svg") return Output::Kind::svg;
  if (ext == "pdf") return Output::Kind::pdf;
  fail("-o: unknown format {} (use .png, .svg or .pdf)", quote(path));
}

std::optional<std::string> title_of(const Spec& spec, const std::vector<Input>& inputs) {
  if (spec.title) return spec.title;
  if (inputs.empty()) return std::nullopt;
  if (auto title = inputs.front().table.meta.get("title")) return title;
  if (auto excitation = inputs.front().table.meta.get("excitation")) return excitation;
  return std::nullopt;
}

std::string build_script(const Spec& spec, const std::vector<Input>& inputs) {
  if (inputs.empty()) fail("no input table");
  const Selection s = select(spec, inputs.front().table);
  std::string out = "# mcg-plot-gnuplot: data inline, edit freely\n";
  out += terminal_lines(spec.output);
  for (std::size_t i = 0; i < inputs.size(); ++i) append_block(out, i + 1, inputs[i].table, s);
  const auto title = title_of(spec, inputs);
  const std::string style = style_of(spec);
  out += "set grid\n";
  out += "set key top right box opaque\n";
  out += "set autoscale xfix\n";

  if (spec.mode == Mode::bode) {
    out += title ? fmt::format("set multiplot layout 2,1 title {}\n", quote(*title)) : "set multiplot layout 2,1\n";
    out += "set logscale x\n";
    out += fmt::format("set xlabel {}\n", quote(label_for("f_hz")));
    for (std::size_t panel = 0; panel < 2; ++panel) {
      out += fmt::format("set ylabel {}\n", quote(label_for(s.y[panel])));
      std::string plot = "plot ";
      for (std::size_t i = 0; i < inputs.size(); ++i) {
        if (i > 0) plot += ", \\\n     ";
        const std::string title_text = inputs.size() == 1 ? "notitle" : "title " + quote(inputs[i].label);
        plot += fmt::format("$data{} using 1:{} with lines linecolor {}{} {}", i + 1, panel + 2, i + 1,
                            dashes(i + 1), title_text);
      }
      out += plot + "\n";
    }
    out += "unset multiplot\n";
  } else if (spec.mode == Mode::rlocus) {
    if (title) out += fmt::format("set title {}\n", quote(*title));
    out += "set autoscale noextend\nset size ratio -1\nset key outside right top box opaque\n";
    out += fmt::format("set xlabel {}\nset ylabel {}\n", quote("real part"), quote("imaginary part"));
    std::string plot = "plot ";
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      if (i > 0) plot += ", \\\n     ";
      plot += fmt::format("$data{} using 1:2 with lines linecolor {}{} title {}", i + 1, i + 1, dashes(i + 1),
                          inputs.size() == 1 ? quote("branches") : quote(inputs[i].label));
    }
    out += rlocus_extras(inputs.front().table, plot);
    out += plot + "\n";
  } else {
    if (title) out += fmt::format("set title {}\n", quote(*title));
    const bool linear = inputs.front().table.meta.get("linear_axis").has_value();
    out += fmt::format("set xlabel {}\n", quote(label_for(s.x, linear)));
    if (!s.y.empty()) out += fmt::format("set ylabel {}\n", quote(join_labels(s.y, linear)));
    if (!s.y2.empty()) {
      out += fmt::format("set y2label {}\n", quote(join_labels(s.y2, linear)));
      out += "set ytics nomirror\nset y2tics\n";
    }
    if (spec.logx) out += "set logscale x\n";
    if (spec.logy) out += fmt::format("set logscale y{}\n", s.y2.empty() ? "" : "y2");
    out += flat_range("yrange", s.y, inputs);
    out += flat_range("y2range", s.y2, inputs);
    std::string plot = "plot ";
    bool first = true;
    const std::vector<std::string> all = joined_names(s.y, s.y2);
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      for (std::size_t j = 0; j < all.size(); ++j) {
        if (!first) plot += ", \\\n     ";
        first = false;
        plot += curve(i + 1, j + 2, j + 1, j >= s.y.size(), style, legend(all[j], inputs, i));
      }
    }
    out += plot + "\n";
  }
  if (spec.output.kind == Output::Kind::png || spec.output.kind == Output::Kind::svg ||
      spec.output.kind == Output::Kind::pdf) {
    out += "unset output\n";
  }
  return out;
}

}  // namespace mcg::plot
