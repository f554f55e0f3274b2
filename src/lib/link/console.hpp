// mcg-serial console: the report's MATLAB GUI as a terminal program. The state, the keys and
// the drawing are pure (unit-tested); console.cpp runs them against the board and ncurses.
#pragma once

#include <cstddef>
#include <deque>
#include <iosfwd>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "link/serial.hpp"  // LinkOptions, RigOptions

namespace mcg::link {

/// One stream sample as the console shows it.
struct ConsoleSample {
  double t_s = 0.0;
  double rpm = 0.0;        ///< measured, NaN while the estimator window fills or a sample was lost
  double rpm_model = 0.0;  ///< the model driven by the measured duty, clutch and load
  double rpm_cmd = 0.0;
  double duty = 0.0;  ///< -1..1
};

/// What a key asks the board (or the console) to do.
struct ConsoleAction {
  enum class Kind {
    none,
    set,
    toggle_clutch,
    toggle_load,
    record_log,
    dump_log,
    load_ini,
    record_csv,
    session_log,
    quit
  };
  Kind kind = Kind::none;
  std::string name;   ///< set: the register
  std::string value;  ///< set: the value as typed; load_ini, dump_log: the file
};

/// Keys the console reads (ncurses codes for the special ones).
inline constexpr int k_key_enter = '\n';
inline constexpr int k_key_escape = 27;
inline constexpr int k_key_backspace = 127;

class ConsoleState {
 public:
  /// `span_s`: seconds of traces kept and drawn.
  explicit ConsoleState(double span_s = 10.0);

  /// Adds a sample; samples older than span_s before the newest leave.
  void add(const ConsoleSample& s);
  const std::deque<ConsoleSample>& samples() const { return m_samples; }
  /// What the screen shows: the samples, or while paused those of the moment `p` was pressed
  /// (the stream, a recording and the session log go on).
  const std::deque<ConsoleSample>& view() const { return paused ? m_frozen : m_samples; }
  double span_s() const { return m_span_s; }

  /// A key: edits the prompt when one is open, else maps the key to an action (a key that
  /// needs a value opens a prompt and returns none until Enter).
  ConsoleAction key(int key);

  std::map<std::string, std::string> registers;  ///< name -> value as the board last said
  std::string status = "connected";              ///< the last result or refusal
  std::string title = "console";                 ///< the screen's first words: the tool's name, "console"
  std::string link_note;                         ///< the line's trouble (a stall, a vanished port), else ""
  bool paused = false;                           ///< the view is frozen (p)
  bool show_help = false;                        ///< the key list replaces the charts (?)
  bool logging = false;                          ///< a session log is written (L)
  bool recording = false;                        ///< a CSV recording runs
  std::string recording_path;
  std::size_t recorded_rows = 0;
  std::size_t lost_samples = 0;
  double residual_rms_rpm = 0.0;  ///< RMS of rpm - rpm_model over the span (finite ones)

  bool prompting() const { return !m_prompt.empty(); }
  std::string prompt_line() const { return m_prompt + m_typed; }

 private:
  std::deque<ConsoleSample> m_samples;
  std::deque<ConsoleSample> m_frozen;  ///< the view while paused
  double m_span_s;
  double m_residual_sq = 0.0;  ///< sum of (rpm - rpm_model)^2 over the span's finite residuals
  std::size_t m_residual_n = 0;
  std::string m_prompt;  ///< "rpm_cmd = " while a value is typed
  std::string m_target;  ///< what the prompt sets
  ConsoleAction::Kind m_prompt_kind = ConsoleAction::Kind::none;
  std::string m_typed;
};

/// A warning when the registers (as get prints them) put a closed loop on gains that make no
/// sense, else "": every gain zero (the controller outputs nothing), a proportional action of
/// the wrong sign (kp <= 0 in p, b0 <= 0 in pi and pid: y[n] = y[n-1] + b0 e[n] + ...), or an
/// integral action of the wrong sign (b0 + b1 (+ b2) < 0: the sum is the gain on e's sum).
std::string closed_loop_warning(const std::map<std::string, std::string>& registers);

/// The keys and what they do, one per line (? shows them).
const std::vector<std::string>& console_key_help();

/// The screen as `height` lines of at most `width` characters: title, a chart of speed
/// (measured '*', model 'o', command '-'), of the residual rpm - model ('x', from 20 lines
/// up) and of duty over the span (or the key list while `?` shows it), the registers, the key
/// line, the warning of closed_loop_warning, the prompt or the status line.
std::vector<std::string> render_console(const ConsoleState& state, int width, int height);

struct ConsoleOptions {
  RigOptions rig;        ///< the rig (supply, load resistor; also the model's INI)
  double span_s = 10.0;  ///< seconds of traces shown
  double poll_s = 1.0;   ///< register poll period
  double seconds = 0.0;  ///< end after this long (0: at q)
  std::string log_path;  ///< a session log from the start (L starts and stops one too)
};

/// One line of the session log: "2026-11-26T16:50:02.125Z TEXT" (UTC, milliseconds) for the
/// time `unix_s` (seconds since 1970).
std::string session_log_line(double unix_s, std::string_view text);

/// console: takes the port (serving every other mcg-serial through it), turns the stream on,
/// and runs the screen until q or `seconds`. When the port vanishes or the stream stops it
/// says so and waits for the port to come back (a recording gets a break row). Actions run on a worker
/// thread as the subcommands do (through this console as the port owner), so neither the
/// stream nor the screen waits for an answer. stdin and stdout must be a terminal. Returns 0.
int run_console(const LinkOptions& link, const ConsoleOptions& options);

}  // namespace mcg::link
