// mcg-serial console: the report's MATLAB GUI as a terminal program. The state, the keys and
// the drawing are pure (unit-tested); console.cpp runs them against the board and ncurses.
#pragma once

#include <cstddef>
#include <deque>
#include <iosfwd>
#include <map>
#include <string>
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
  enum class Kind { none, set, toggle_clutch, toggle_load, record_log, dump_log, load_ini, record_csv, quit };
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
  double span_s() const { return m_span_s; }

  /// A key: edits the prompt when one is open, else maps the key to an action (a key that
  /// needs a value opens a prompt and returns none until Enter).
  ConsoleAction key(int key);

  std::map<std::string, std::string> registers;  ///< name -> value as the board last said
  std::string status = "connected";              ///< the last result or refusal
  bool recording = false;                        ///< a CSV recording runs
  std::string recording_path;
  std::size_t recorded_rows = 0;
  std::size_t lost_samples = 0;
  double residual_rms_rpm = 0.0;  ///< RMS of rpm - rpm_model over the span (finite ones)

  bool prompting() const { return !m_prompt.empty(); }
  std::string prompt_line() const { return m_prompt + m_typed; }

 private:
  std::deque<ConsoleSample> m_samples;
  double m_span_s;
  double m_residual_sq = 0.0;  ///< sum of (rpm - rpm_model)^2 over the span's finite residuals
  std::size_t m_residual_n = 0;
  std::string m_prompt;  ///< "rpm_cmd = " while a value is typed
  std::string m_target;  ///< what the prompt sets
  ConsoleAction::Kind m_prompt_kind = ConsoleAction::Kind::none;
  std::string m_typed;
};

/// The screen as `height` lines of at most `width` characters: title, a chart of speed
/// (measured '*', model 'o', command '-') and duty below it over the span, the registers,
/// the key help, the prompt or the status line.
std::vector<std::string> render_console(const ConsoleState& state, int width, int height);

struct ConsoleOptions {
  RigOptions rig;        ///< the rig (supply, load resistor; also the model's INI)
  double span_s = 10.0;  ///< seconds of traces shown
  double poll_s = 1.0;   ///< register poll period
  double seconds = 0.0;  ///< end after this long (0: at q)
};

/// console: takes the port (serving every other mcg-serial through it), turns the stream on,
/// and runs the screen until q, the port vanishing, or `seconds`. Actions run on a worker
/// thread as the subcommands do (through this console as the port owner), so neither the
/// stream nor the screen waits for an answer. stdin and stdout must be a terminal. Returns 0.
int run_console(const LinkOptions& link, const ConsoleOptions& options);

}  // namespace mcg::link
