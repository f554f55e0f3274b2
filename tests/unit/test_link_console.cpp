// The console's state, keys and screen, without a board or a terminal.
#include <gtest/gtest.h>

#include <cmath>

#include <map>
#include <string>

#include "link/console.hpp"

namespace mcg::link {
namespace {

ConsoleAction type(ConsoleState& s, const std::string& keys) {
  ConsoleAction last;
  for (char c : keys) last = s.key(c == '\n' ? k_key_enter : c);
  return last;
}

TEST(LinkConsole, AKeyWithAValueOpensAPromptAndEnterGivesTheAction) {
  ConsoleState s;
  EXPECT_EQ(s.key('r').kind, ConsoleAction::Kind::none);
  EXPECT_TRUE(s.prompting());
  EXPECT_EQ(s.prompt_line(), "rpm_cmd = ");
  // While typing, the command keys are text.
  const ConsoleAction a = type(s, "5q0\n");
  EXPECT_EQ(a.kind, ConsoleAction::Kind::set);
  EXPECT_EQ(a.name, "rpm_cmd");
  EXPECT_EQ(a.value, "5q0");
  EXPECT_FALSE(s.prompting());
}

TEST(LinkConsole, SetAnyNamesTheRegisterFirstAndEscapeCancels) {
  ConsoleState s;
  const ConsoleAction a = type(s, "sb0 1.25\n");
  EXPECT_EQ(a.kind, ConsoleAction::Kind::set);
  EXPECT_EQ(a.name, "b0");
  EXPECT_EQ(a.value, "1.25");
  type(s, "d12");
  s.key(k_key_backspace);
  EXPECT_EQ(s.prompt_line(), "duty (%) = 1");
  EXPECT_EQ(s.key(k_key_escape).kind, ConsoleAction::Kind::none);
  EXPECT_FALSE(s.prompting());
  EXPECT_EQ(s.status, "cancelled");
}

TEST(LinkConsole, ToggleAndQuitKeysActAtOnceAndWStopsARecording) {
  ConsoleState s;
  EXPECT_EQ(s.key('c').kind, ConsoleAction::Kind::toggle_clutch);
  EXPECT_EQ(s.key('l').kind, ConsoleAction::Kind::toggle_load);
  EXPECT_EQ(s.key('q').kind, ConsoleAction::Kind::quit);
  EXPECT_EQ(type(s, "wrun.csv\n").value, "run.csv");
  s.recording = true;
  const ConsoleAction stop = s.key('w');
  EXPECT_EQ(stop.kind, ConsoleAction::Kind::record_csv);
  EXPECT_TRUE(stop.value.empty());
}

TEST(LinkConsole, KeepsTheSpanAndTheResidualRms) {
  ConsoleState s(1.0);
  for (int n = 0; n <= 1000; ++n) s.add({n * 0.004, 500.0, 497.0, 500.0, 0.3});
  EXPECT_EQ(s.samples().size(), 251U);  // 1 s of 4 ms samples, both ends
  EXPECT_DOUBLE_EQ(s.residual_rms_rpm, 3.0);
}

// The RMS covers the span only: residuals that left the span (10 rpm) no longer count, samples
// without a measured speed (NaN while the estimator fills) never do.
TEST(LinkConsole, TheResidualRmsForgetsWhatLeftTheSpan) {
  ConsoleState s(1.0);
  for (int n = 0; n < 500; ++n) s.add({n * 0.004, 510.0, 500.0, 500.0, 0.3});
  EXPECT_DOUBLE_EQ(s.residual_rms_rpm, 10.0);
  for (int n = 500; n < 1000; ++n) {
    const double rpm = n % 2 == 0 ? std::nan("") : 502.0;
    s.add({n * 0.004, rpm, 500.0, 500.0, 0.3});
  }
  EXPECT_NEAR(s.residual_rms_rpm, 2.0, 1e-9);
  EXPECT_EQ(s.samples().size(), 251U);
}

TEST(LinkConsole, TheScreenDrawsMeasuredModelCommandAndStatus) {
  ConsoleState s(1.0);
  for (int n = 0; n <= 250; ++n) s.add({n * 0.004, 100.0 + n, 90.0 + n, 420.0, 0.5});
  s.registers["mode"] = "pi";
  s.status = "rpm_cmd = 420";
  const auto lines = render_console(s, 100, 30);
  ASSERT_EQ(lines.size(), 30U);
  std::string all;
  for (const auto& l : lines) {
    EXPECT_LE(l.size(), 100U);
    all += l + "\n";
  }
  EXPECT_NE(lines[0].find("rpm 350"), std::string::npos) << lines[0];
  // The title is the caller's (the tool's name): the library names none.
  EXPECT_EQ(lines[0].rfind("console", 0), 0U) << lines[0];
  s.title = "mcg-serial console";
  EXPECT_EQ(render_console(s, 100, 30)[0].rfind("mcg-serial console", 0), 0U);
  EXPECT_NE(all.find('*'), std::string::npos);
  EXPECT_NE(all.find('o'), std::string::npos);
  EXPECT_NE(all.find("---"), std::string::npos);
  EXPECT_NE(all.find("board: mode pi"), std::string::npos);
  EXPECT_EQ(lines.back(), "rpm_cmd = 420");
  EXPECT_NE(render_console(s, 30, 8)[0].find("too small: 40x12 at least"), std::string::npos);
}

TEST(LinkConsole, PFreezesTheViewWhileTheSamplesGoOn) {
  ConsoleState s(1.0);
  for (int n = 0; n < 10; ++n) s.add({n * 0.004, 100.0, 100.0, 420.0, 0.5});
  EXPECT_EQ(type(s, "p").kind, ConsoleAction::Kind::none);
  EXPECT_TRUE(s.paused);
  for (int n = 10; n < 20; ++n) s.add({n * 0.004, 200.0, 100.0, 420.0, 0.5});
  EXPECT_EQ(s.samples().size(), 20U);
  ASSERT_EQ(s.view().size(), 10U);
  EXPECT_DOUBLE_EQ(s.view().back().rpm, 100.0);
  EXPECT_NE(render_console(s, 100, 30)[0].find("PAUSED"), std::string::npos);
  type(s, "p");
  EXPECT_FALSE(s.paused);
  EXPECT_EQ(s.view().size(), 20U);
  EXPECT_EQ(render_console(s, 100, 30)[0].find("PAUSED"), std::string::npos);
}

TEST(LinkConsole, QuestionMarkShowsEveryKeyAndHidesItAgain) {
  ConsoleState s;
  type(s, "?");
  ASSERT_TRUE(s.show_help);
  std::string all;
  for (const auto& l : render_console(s, 100, 30)) all += l + "\n";
  for (const char* key : {"  r  ", "  d  ", "  m  ", "  w  ", "  p  ", "  L  ", "  ?  ", "  q  "}) {
    EXPECT_NE(all.find(key), std::string::npos) << key << "\n" << all;
  }
  type(s, "?");
  EXPECT_FALSE(s.show_help);
}

TEST(LinkConsole, LAsksForTheSessionLogAndLAgainStopsIt) {
  ConsoleState s;
  const ConsoleAction a = type(s, "Llab.log\n");
  EXPECT_EQ(a.kind, ConsoleAction::Kind::session_log);
  EXPECT_EQ(a.value, "lab.log");
  s.logging = true;
  EXPECT_EQ(type(s, "L").kind, ConsoleAction::Kind::session_log);
  EXPECT_FALSE(s.prompting());
}

TEST(LinkConsole, TheResidualIsATraceOfItsOwn) {
  ConsoleState s(1.0);
  for (int n = 0; n <= 250; ++n) s.add({n * 0.004, 100.0 + 20.0 * (n % 2), 100.0, 420.0, 0.5});
  const auto lines = render_console(s, 100, 30);
  std::size_t label = lines.size();
  for (std::size_t k = 0; k < lines.size(); ++k) {
    if (lines[k].find("residual, rpm: x measured - model") != std::string::npos) label = k;
  }
  ASSERT_LT(label, lines.size());
  // +20 at the top row, 0 in the middle row of the three.
  EXPECT_NE(lines[label + 1].find('x'), std::string::npos);
  EXPECT_NE(lines[label + 2].find('x'), std::string::npos);
  EXPECT_EQ(lines[label + 3].find('x'), std::string::npos);
}

TEST(LinkConsole, AClosedLoopOnGainsThatMakeNoSenseIsWarnedOf) {
  std::map<std::string, std::string> r{{"mode", "open"}, {"kp", "0"}, {"b0", "0"}, {"b1", "0"}, {"b2", "0"}};
  EXPECT_EQ(closed_loop_warning(r), "");
  r["mode"] = "pi";
  EXPECT_EQ(closed_loop_warning(r), "WARNING: mode pi with every gain zero: the controller outputs nothing");
  r["b0"] = "6.5";
  r["b1"] = "-3.9";
  EXPECT_EQ(closed_loop_warning(r), "");
  r["b1"] = "-7";
  EXPECT_EQ(closed_loop_warning(r),
            "WARNING: mode pi with b0 = 6.5, b1 = -7: the integral gain (their sum) is negative, the speed "
            "runs away");
  r["b0"] = "-1";
  r["b1"] = "2";
  EXPECT_EQ(closed_loop_warning(r), "WARNING: mode pi with b0 = -1, b1 = 2: b0 <= 0 acts against the error");
  r["mode"] = "p";
  EXPECT_EQ(closed_loop_warning(r), "WARNING: mode p with kp = 0: the controller outputs nothing");
  r["kp"] = "-3";
  EXPECT_EQ(closed_loop_warning(r), "WARNING: mode p with kp = -3: positive feedback, the speed runs away");
  r["mode"] = "pid";
  r["b0"] = "10";
  r["b1"] = "-15";
  r["b2"] = "6";
  EXPECT_EQ(closed_loop_warning(r), "");
  r.erase("b2");
  EXPECT_EQ(closed_loop_warning(r), "") << "a gain not read yet: no verdict";
  ConsoleState s;
  s.registers = {{"mode", "p"}, {"kp", "0"}};
  EXPECT_EQ(render_console(s, 100, 30)[28], "WARNING: mode p with kp = 0: the controller outputs nothing");
}

TEST(LinkConsole, SessionLogLinesCarryUtcTimeToTheMillisecond) {
  EXPECT_EQ(session_log_line(0.0, "start"), "1970-01-01T00:00:00.000Z start");
  EXPECT_EQ(session_log_line(1795712402.1254, "key r: rpm_cmd 500"),
            "2026-11-26T17:00:02.125Z key r: rpm_cmd 500");
}

}  // namespace
}  // namespace mcg::link
