// gnuplot script building: exact text for simple cases, quoting, labels, errors.
#include "plot/script.hpp"

#include "common/error.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

namespace mcg::plot {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

Input input(const std::string& csv, const std::string& label = "stdin") {
  std::istringstream in(csv);
  return {table::read(in, "<stdin>"), label};
}

TEST(PlotQuote, DoublesSingleQuotesAndDropsControlCharacters) {
  EXPECT_EQ(quote("rpm"), "'rpm'");
  EXPECT_EQ(quote("it's"), R"('it'."'".'s')");
  EXPECT_EQ(quote("'"), R"(''."'".'')");
  EXPECT_EQ(quote("a\nsystem('ls')\r\x1b[2J\x7f"), R"('asystem('."'".'ls'."'".')[2J')");
  EXPECT_EQ(quote("x\"; system(\"touch pwned\"); \""), "'x\"; system(\"touch pwned\"); \"'");
  EXPECT_EQ(quote("`id` @macro \\n"), "'`id` @macro \\n'");
  EXPECT_EQ(quote("Ω"), "'Ω'");
}

TEST(PlotLabels, CarryTheDataContractUnits) {
  EXPECT_EQ(label_for("t"), "t (s)");
  EXPECT_EQ(label_for("rpm"), "rpm (rev/min)");
  EXPECT_EQ(label_for("v"), "v (V)");
  EXPECT_EQ(label_for("i"), "i (A)");
  EXPECT_EQ(label_for("omega"), "omega (rad/s)");
  EXPECT_EQ(label_for("r_load"), "r_load (ohm)");
  EXPECT_EQ(label_for("f_hz"), "frequency (Hz)");
  EXPECT_EQ(label_for("mystery"), "mystery");
}

TEST(PlotLabels, AReportsColumnsTakeTheirMeasurementsUnit) {
  EXPECT_EQ(label_for("rpm_res_after"), "rpm_res_after (rev/min)");
  EXPECT_EQ(label_for("omega_before"), "omega_before (rad/s)");
  EXPECT_EQ(label_for("i_after"), "i_after (A)");
  EXPECT_EQ(label_for("mystery_after"), "mystery_after");
  EXPECT_EQ(label_for("_after"), "_after");
}

TEST(PlotLabels, ALinearAxisSpeedIsInMetresPerSecond) {
  EXPECT_EQ(label_for("omega", true), "omega (m/s)");
  EXPECT_EQ(label_for("omega_res_before", true), "omega_res_before (m/s)");
  EXPECT_EQ(label_for("theta", true), "theta (m)");
  EXPECT_EQ(label_for("t", true), "t (s)");
  Spec spec;
  spec.output = {Output::Kind::svg, "axis.svg", "", 800, 600};
  const auto script = build_script(spec, {input("# linear_axis: yes\nt,omega\n0,0.1\n0.001,0.2\n")});
  EXPECT_NE(script.find("\nset ylabel 'omega (m/s)'\n"), std::string::npos);
}

TEST(PlotKind, FollowsTheExtension) {
  EXPECT_EQ(kind_from_path("a.png"), Output::Kind::png);
  EXPECT_EQ(kind_from_path("dir.x/A.SVG"), Output::Kind::svg);
  EXPECT_EQ(kind_from_path("report.pdf"), Output::Kind::pdf);
  EXPECT_THAT([] { kind_from_path("a.gif"); },
              ThrowsMessage<Error>("-o: unknown format 'a.gif' (use .png, .svg or .pdf)"));
  EXPECT_THAT([] { kind_from_path("png"); }, ThrowsMessage<Error>(HasSubstr("unknown format 'png'")));
}

TEST(PlotScript, SeriesToPngExactly) {
  Spec spec;
  spec.y = {"rpm"};
  spec.y2 = {"i"};
  spec.output = {Output::Kind::png, "step.png", "", 1000, 600};
  const auto script = build_script(spec, {input("# title: 12 V step\nt,v,rpm,i\n0,0,0,0\n0.001,12,1.5,3.25\n")});
  EXPECT_EQ(script,
            "# mcg-plot-gnuplot: data inline, edit freely\n"
            "set terminal pngcairo size 1000,600 noenhanced font 'sans,10'\n"
            "set output 'step.png'\n"
            "$data1 << EOD\n"
            "0 0 0\n"
            "0.001 1.5 3.25\n"
            "EOD\n"
            "set grid\n"
            "set key top right box opaque\n"
            "set autoscale xfix\n"
            "set title '12 V step'\n"
            "set xlabel 't (s)'\n"
            "set ylabel 'rpm (rev/min)'\n"
            "set y2label 'i (A)'\n"
            "set ytics nomirror\n"
            "set y2tics\n"
            "plot $data1 using 1:2 with lines linecolor 1 title 'rpm', \\\n"
            "     $data1 using 1:3 axes x1y2 with lines linecolor 2 title 'i'\n"
            "unset output\n");
}

// An axis with one value (a live window of a shaft at rest, a constant current) gets the range
// gnuplot would widen it to, so gnuplot does not warn; an axis with any spread is autoscaled.
TEST(PlotScript, AFlatAxisGetsItsRangeSet) {
  Spec spec;
  spec.y = {"rpm"};
  spec.y2 = {"i"};
  spec.output = {Output::Kind::dumb, "", "", 80, 24};
  const auto flat = build_script(spec, {input("t,rpm,i\n0,0,0.5\n0.004,nan,0.5\n0.008,0,0.5\n")});
  EXPECT_NE(flat.find("set yrange [-1:1]\n"), std::string::npos) << flat;
  EXPECT_NE(flat.find("set y2range [0.495:0.505]\n"), std::string::npos) << flat;
  const auto spread = build_script(spec, {input("t,rpm,i\n0,0,0.5\n0.004,2,0.5\n")});
  EXPECT_EQ(spread.find("set yrange"), std::string::npos) << spread;
  EXPECT_NE(spread.find("set y2range [0.495:0.505]\n"), std::string::npos) << spread;
}

TEST(PlotScript, DumbStepsWithDefaultColumnsAndMissingValues) {
  Spec spec;
  spec.steps = true;
  spec.title = "override";
  spec.output = {Output::Kind::dumb, "", "", 100, 30};
  const auto script = build_script(spec, {input("# excitation: prbs\nt,v,rpm\n0,1,nan\n1,-1,inf\n2,1,5\n")});
  EXPECT_EQ(script,
            "# mcg-plot-gnuplot: data inline, edit freely\n"
            "set terminal dumb size 100,30 noenhanced\n"
            "$data1 << EOD\n"
            "0 1 NaN\n"
            "1 -1 NaN\n"
            "2 1 5\n"
            "EOD\n"
            "set grid\n"
            "set key top right box opaque\n"
            "set autoscale xfix\n"
            "set title 'override'\n"
            "set xlabel 't (s)'\n"
            "set ylabel 'v (V), rpm (rev/min)'\n"
            "plot $data1 using 1:2 with steps linecolor 1 title 'v', \\\n"
            "     $data1 using 1:3 with steps linecolor 2 title 'rpm'\n");
}

TEST(PlotScript, DefaultColumnsLeaveOutOneWithNothingToDraw) {
  Spec spec;
  spec.output = {Output::Kind::dumb, "", "", 100, 30};
  const auto script = build_script(spec, {input("t,v,r_load,rpm\n0,1,inf,0\n1,2,inf,5\n")});
  EXPECT_NE(script.find("title 'v'"), std::string::npos) << script;
  EXPECT_NE(script.find("title 'rpm'"), std::string::npos) << script;
  EXPECT_EQ(script.find("r_load"), std::string::npos) << script;
}

TEST(PlotScript, BodePanelsWithOverlay) {
  Spec spec;
  spec.mode = Mode::bode;
  spec.output = {Output::Kind::svg, "b.svg", "", 800, 700};
  const std::string csv = "f_hz,mag_db,phase_deg,coherence\n1,20,-5,1\n10,0,-90,0.9\n";
  const auto script = build_script(spec, {input(csv, "measured.csv"), input(csv, "sim.csv")});
  EXPECT_EQ(script,
            "# mcg-plot-gnuplot: data inline, edit freely\n"
            "set terminal svg size 800,700 noenhanced font 'sans,10' background '#ffffff'\n"
            "set output 'b.svg'\n"
            "$data1 << EOD\n1 20 -5\n10 0 -90\nEOD\n"
            "$data2 << EOD\n1 20 -5\n10 0 -90\nEOD\n"
            "set grid\n"
            "set key top right box opaque\n"
            "set autoscale xfix\n"
            "set multiplot layout 2,1\n"
            "set logscale x\n"
            "set xlabel 'frequency (Hz)'\n"
            "set ylabel 'magnitude (dB)'\n"
            "plot $data1 using 1:2 with lines linecolor 1 title 'measured.csv', \\\n"
            "     $data2 using 1:2 with lines linecolor 2 dashtype 2 title 'sim.csv'\n"
            "set ylabel 'phase (deg)'\n"
            "plot $data1 using 1:3 with lines linecolor 1 title 'measured.csv', \\\n"
            "     $data2 using 1:3 with lines linecolor 2 dashtype 2 title 'sim.csv'\n"
            "unset multiplot\n"
            "unset output\n");
}

TEST(PlotScript, OverlayKeepsColoursPerColumnAndNamesFiles) {
  Spec spec;
  spec.y = {"rpm", "i"};
  const auto script = build_script(spec, {input("t,rpm,i\n0,1,2\n", "run1.csv"), input("t,i,rpm\n0,3,4\n", "sim.csv")});
  EXPECT_THAT(script, HasSubstr("$data2 << EOD\n0 4 3\nEOD\n"));
  EXPECT_THAT(script, HasSubstr("$data1 using 1:2 with lines linecolor 1 title 'rpm (run1.csv)'"));
  EXPECT_THAT(script, HasSubstr("$data2 using 1:3 with lines linecolor 2 dashtype 2 title 'i (sim.csv)'"));
  EXPECT_THAT(script, HasSubstr("set termoption noenhanced\n"));
}

TEST(PlotScript, XyDrawsPointsAgainstAnyColumn) {
  Spec spec;
  spec.mode = Mode::xy;
  spec.x = "v";
  spec.y = {"i"};
  const auto script = build_script(spec, {input("t,v,i\n0,2,1\n1,1,0.5\n")});
  EXPECT_THAT(script, HasSubstr("$data1 << EOD\n2 1\n1 0.5\nEOD\n"));
  EXPECT_THAT(script, HasSubstr("set xlabel 'v (V)'\n"));
  EXPECT_THAT(script, HasSubstr("with points pointtype 7 pointsize 0.5 linecolor 1 title 'i'"));
}

TEST(PlotScript, BranchesAreSeparateLines) {
  // Rows k-major as mcg-design rlocus writes them; each branch must be drawn on its own.
  const char* csv = "k,branch,re,im\n0,1,-2,0\n0,2,0,0\n1,1,-1,0\n1,2,-1,0\n2,1,-1,-1\n2,2,-1,1\n";
  Spec spec;
  spec.x = "re";
  spec.y = {"im"};
  EXPECT_THAT(build_script(spec, {input(csv)}), HasSubstr("$data1 << EOD\n-2 0\n-1 0\n-1 -1\n\n0 0\n-1 0\n-1 1\nEOD\n"));
}

TEST(PlotScript, RootLocusWithPolesAsymptotesAndBoundary) {
  const char* csv =
      "# asymptote_centre: -1\n# asymptote_angles_deg: 90 270\n# boundary: imaginary axis\n"
      "k,branch,re,im\n0,1,-2,0\n0,2,0,0\n1,1,-1,0\n1,2,-1,0\n2,1,-1,-1\n2,2,-1,1\n";
  Spec spec;
  spec.mode = Mode::rlocus;
  const auto script = build_script(spec, {input(csv)});
  EXPECT_THAT(script, HasSubstr("$data1 << EOD\n-2 0\n-1 0\n-1 -1\n\n0 0\n-1 0\n-1 1\nEOD\n"));
  EXPECT_THAT(script, HasSubstr("$poles << EOD\n-2 0\n0 0\nEOD\n"));
  // Rays from -1 as long as the locus reaches from there (1): to (-1, 1) and (-1, -1), up to rounding.
  EXPECT_THAT(script, HasSubstr("$asymptotes << EOD\n-1 0\n-0.9999999999999999 1\n\n-1 0\n-1.0000000000000002 -1\n\nEOD\n"));
  EXPECT_THAT(script, HasSubstr("set yzeroaxis"));
  EXPECT_THAT(script, HasSubstr("set size ratio -1\n"));
  const auto z = build_script(spec, {input("# boundary: unit circle\nk,branch,re,im\n0,1,0.5,0\n1,1,0.2,0\n")});
  EXPECT_THAT(z, HasSubstr("set object 1 circle at 0,0 size 1"));
}

TEST(PlotScript, HostileNamesAndTitlesStayInsideStringLiterals) {
  Spec spec;
  spec.output = {Output::Kind::png, "o'x.png", "", 100, 100};
  const auto script = build_script(
      spec, {input("# title: a' ; system('touch pwned') ; '\nt,x\"; system(\"touch pwned\"); \",`touch pwned`\n0,1,2\n",
                   "f'\n.csv")});
  EXPECT_THAT(script, HasSubstr(R"(set output 'o'."'".'x.png')"));
  EXPECT_THAT(script, HasSubstr(R"(set title 'a'."'".' ; system('."'".'touch pwned'."'".') ; '."'".'')"));
  EXPECT_THAT(script, HasSubstr("title 'x\"; system(\"touch pwned\"); \"'"));
  EXPECT_THAT(script, HasSubstr("title '`touch pwned`'"));
  // Every line outside the data block is a known command; no data text starts a line.
  std::istringstream lines(script);
  std::string line;
  bool in_data = false;
  while (std::getline(lines, line)) {
    if (line.rfind("$data", 0) == 0 && line.find("<< EOD") != std::string::npos) {
      in_data = true;
      continue;
    }
    if (line == "EOD") {
      in_data = false;
      continue;
    }
    if (in_data) continue;
    const bool known = line.rfind("set ", 0) == 0 || line.rfind("plot ", 0) == 0 || line.rfind("     $data", 0) == 0 ||
                       line.rfind("unset ", 0) == 0 || line.rfind("# ", 0) == 0;
    EXPECT_TRUE(known) << line;
  }
}

TEST(PlotScript, ErrorsNameTheTableAndColumn) {
  Spec spec;
  spec.y = {"rpm"};
  EXPECT_THAT([&] { build_script(spec, {input("t,v\n0,1\n")}); },
              ThrowsMessage<Error>("<stdin>: missing column 'rpm' (has: t,v)"));
  spec.y = {"v"};
  EXPECT_THAT([&] { build_script(spec, {input("t,v\n0,nan\n")}); },
              ThrowsMessage<Error>("<stdin>: column 'v' has no finite value to plot"));
  spec.y.clear();
  EXPECT_THAT([&] { build_script(spec, {input("t\n0\n")}); },
              ThrowsMessage<Error>("<stdin>: no column to plot besides 't'"));
  EXPECT_THAT([&] { build_script(spec, {input("t,r_load\n0,inf\n")}); },
              ThrowsMessage<Error>("<stdin>: no column to plot besides 't'"));
  spec.mode = Mode::bode;
  EXPECT_THAT([&] { build_script(spec, {input("f_hz,mag_db\n1,0\n")}); },
              ThrowsMessage<Error>("<stdin>: missing column 'phase_deg' (has: f_hz,mag_db)"));
}

}  // namespace
}  // namespace mcg::plot
