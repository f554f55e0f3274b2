// mcg-serial console (see console.hpp): the state and its drawing, and the loop that runs
// them against the board. ncurses is used for the terminal only: keys in, lines out.
#include "link/console.hpp"

#include <curses.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <limits>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "boardunits/fixed_point.hpp"  // board_mode
#include "common/error.hpp"
#include "common/quote.hpp"
#include "common/units.hpp"
#include "config/ini.hpp"
#include "link/capture_meta.hpp"
#include "link/connection.hpp"
#include "link/interrupt.hpp"
#include "link/port.hpp"
#include "link/stream_block.hpp"
#include "model/load.hpp"
#include "model/model.hpp"
#include "table/table.hpp"

namespace mcg::link {

ConsoleState::ConsoleState(double span_s) : m_span_s(span_s) {}

void ConsoleState::add(const ConsoleSample& s) {
  // The residual's sums follow the samples in and out: constant work a sample, however long
  // the span, so the stream never waits for the screen's arithmetic.
  const auto tally = [this](const ConsoleSample& x, double sign) {
    const double r = x.rpm - x.rpm_model;
    if (!std::isfinite(r)) return;
    m_residual_sq += sign * r * r;
    m_residual_n = sign > 0 ? m_residual_n + 1 : m_residual_n - 1;
  };
  m_samples.push_back(s);
  tally(s, 1.0);
  while (m_samples.front().t_s < s.t_s - m_span_s) {
    tally(m_samples.front(), -1.0);
    m_samples.pop_front();
  }
  if (m_residual_n == 0) m_residual_sq = 0.0;  // no rounding left over from samples gone
  residual_rms_rpm =
      m_residual_n > 0 ? std::sqrt(std::max(m_residual_sq, 0.0) / static_cast<double>(m_residual_n)) : 0.0;
}

ConsoleAction ConsoleState::key(int key) {
  using Kind = ConsoleAction::Kind;
  if (prompting()) {
    if (key == k_key_escape) {
      m_prompt.clear();
      m_typed.clear();
      status = "cancelled";
    } else if (key == k_key_backspace || key == KEY_BACKSPACE || key == 8) {
      if (!m_typed.empty()) m_typed.pop_back();
    } else if (key == k_key_enter || key == '\r' || key == KEY_ENTER) {
      ConsoleAction a;
      a.kind = m_prompt_kind;
      a.name = m_target;
      a.value = m_typed;
      if (a.kind == Kind::set && a.name.empty()) {
        // "set NAME VALUE": the first word names the register.
        const auto space = m_typed.find(' ');
        a.name = m_typed.substr(0, space);
        a.value = space == std::string::npos ? "" : m_typed.substr(space + 1);
      }
      m_prompt.clear();
      m_typed.clear();
      return a;
    } else if (key >= 32 && key < 127) {
      m_typed += static_cast<char>(key);
    }
    return {};
  }
  auto ask = [&](std::string prompt, Kind kind, std::string target) {
    m_prompt = std::move(prompt);
    m_prompt_kind = kind;
    m_target = std::move(target);
    return ConsoleAction{};
  };
  switch (key) {
    case 'r':
      return ask("rpm_cmd = ", Kind::set, "rpm_cmd");
    case 'd':
      return ask("duty (%) = ", Kind::set, "duty");
    case 'm':
      return ask("mode (open, p, pi, pid) = ", Kind::set, "mode");
    case 'k':
      return ask("kp = ", Kind::set, "kp");
    case 's':
      return ask("set (register value) ", Kind::set, "");
    case 'c':
      return {Kind::toggle_clutch, "clutch", ""};
    case 'l':
      return {Kind::toggle_load, "load", ""};
    case 'g':
      return ask("record the RAM log and dump it to: ", Kind::record_log, "");
    case 'D':
      return ask("dump the RAM log to: ", Kind::dump_log, "");
    case 'o':
      return ask("load design INI: ", Kind::load_ini, "");
    case 'w':
      if (recording) return {Kind::record_csv, "", ""};
      return ask("record the stream to: ", Kind::record_csv, "");
    case 'L':
      if (logging) return {Kind::session_log, "", ""};
      return ask("session log to: ", Kind::session_log, "");
    case 'p':
      paused = !paused;
      if (paused) m_frozen = m_samples;
      status = paused ? "view paused (p resumes; the stream and any recording go on)" : "view resumed";
      return {};
    case '?':
      show_help = !show_help;
      return {};
    case 'q':
      return {Kind::quit, "", ""};
    default:
      return {};
  }
}

namespace {

std::string fit(std::string line, int width) {
  if (width <= 0) return {};
  if (line.size() > static_cast<std::size_t>(width)) line.resize(static_cast<std::size_t>(width));
  return line;
}

/// Draws `series` (value of a sample, a mark) into rows [top, top + rows) of `grid` over the
/// samples' time span, with the value range [lo, hi] and labels in the left margin.
void chart(std::vector<std::string>& grid, int top, int rows, int left, int width,
           const std::deque<ConsoleSample>& samples, double lo, double hi,
           const std::vector<std::pair<double (*)(const ConsoleSample&), char>>& series) {
  if (samples.empty() || rows < 2 || width - left < 10) return;
  const double t0 = samples.front().t_s;
  const double t1 = std::max(samples.back().t_s, t0 + 1e-9);
  const int cols = width - left;
  for (const auto& [value, mark] : series) {
    for (const ConsoleSample& s : samples) {
      const double v = value(s);
      if (!std::isfinite(v)) continue;
      const int col = left + static_cast<int>(std::lround((s.t_s - t0) / (t1 - t0) * (cols - 1)));
      const double frac = hi > lo ? (v - lo) / (hi - lo) : 0.5;
      const int row = top + rows - 1 - static_cast<int>(std::lround(std::clamp(frac, 0.0, 1.0) * (rows - 1)));
      grid[static_cast<std::size_t>(row)][static_cast<std::size_t>(col)] = mark;
    }
  }
  const std::string hi_label = fmt::format("{:>{}.0f}|", hi, left - 1);
  const std::string lo_label = fmt::format("{:>{}.0f}|", lo, left - 1);
  for (int r = top; r < top + rows; ++r)
    grid[static_cast<std::size_t>(r)].replace(0, static_cast<std::size_t>(left),
                                              std::string(static_cast<std::size_t>(left - 1), ' ') + "|");
  grid[static_cast<std::size_t>(top)].replace(0, hi_label.size(), hi_label);
  grid[static_cast<std::size_t>(top + rows - 1)].replace(0, lo_label.size(), lo_label);
}

std::string reg(const ConsoleState& s, const std::string& name) {
  const auto it = s.registers.find(name);
  return it == s.registers.end() ? "?" : it->second;
}

}  // namespace

std::string closed_loop_warning(const std::map<std::string, std::string>& registers) {
  const auto it = registers.find("mode");
  if (it == registers.end()) return {};
  const std::optional<std::int16_t> mode_id = boardunits::board_mode(it->second);
  if (!mode_id || *mode_id == MCG_MODE_OPEN) return {};
  const std::string& mode = it->second;
  const auto gain = [&](const char* name) -> std::optional<double> {
    const auto g = registers.find(name);
    if (g == registers.end()) return std::nullopt;
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(g->second.data(), g->second.data() + g->second.size(), v);
    if (ec != std::errc() || ptr != g->second.data() + g->second.size()) return std::nullopt;
    return v;
  };
  const auto b0 = gain("b0"), b1 = gain("b1"), b2 = gain("b2"), kp = gain("kp");
  if (mode == "p") {
    if (!kp) return {};
    if (*kp == 0.0) return "WARNING: mode p with kp = 0: the controller outputs nothing";
    if (*kp < 0.0)
      return fmt::format("WARNING: mode p with kp = {}: positive feedback, the speed runs away", *kp);
    return {};
  }
  if (!b0 || !b1 || (mode == "pid" && !b2)) return {};
  const double integral = *b0 + *b1 + (mode == "pid" ? *b2 : 0.0);
  const std::string gains = mode == "pid" ? fmt::format("b0 = {}, b1 = {}, b2 = {}", *b0, *b1, *b2)
                                          : fmt::format("b0 = {}, b1 = {}", *b0, *b1);
  if (*b0 == 0.0 && *b1 == 0.0 && (mode != "pid" || *b2 == 0.0)) {
    return fmt::format("WARNING: mode {} with every gain zero: the controller outputs nothing", mode);
  }
  if (*b0 <= 0.0) return fmt::format("WARNING: mode {} with {}: b0 <= 0 acts against the error", mode, gains);
  if (integral < 0.0) {
    return fmt::format(
        "WARNING: mode {} with {}: the integral gain (their sum) is negative, the speed runs away", mode,
        gains);
  }
  return {};
}

const std::vector<std::string>& console_key_help() {
  static const std::vector<std::string> k_help = {
      "keys (? closes this list):",
      "  r  speed command (rpm_cmd)          d  duty, % (mode open)",
      "  m  mode (open, p, pi, pid)          k  kp",
      "  s  set any register: NAME VALUE     c  clutch on/off    l  load on/off",
      "  g  record the RAM log and dump it   D  dump the RAM log",
      "  o  load a design INI                w  record the stream to CSV (w again stops)",
      "  p  pause/resume the view            L  session log to a file (L again stops)",
      "  ?  this list                        q  quit",
      "  Enter confirms a prompt, Esc cancels it",
  };
  return k_help;
}

std::vector<std::string> render_console(const ConsoleState& state, int width, int height) {
  std::vector<std::string> grid(static_cast<std::size_t>(std::max(height, 0)),
                                std::string(static_cast<std::size_t>(std::max(width, 0)), ' '));
  if (height < 12 || width < 40) {
    if (height > 0) grid[0] = fit("too small: 40x12 at least", width);
    return grid;
  }
  const auto& samples = state.view();
  std::string title = state.title;
  if (state.paused) title += "   PAUSED";
  if (!samples.empty()) {
    const ConsoleSample& last = samples.back();
    title += fmt::format(
        "   t {:.1f} s   rpm {:.0f}   model {:.0f}   cmd {:.0f}   duty {:.1f} %   residual RMS {:.1f} rpm",
        last.t_s, last.rpm, last.rpm_model, last.rpm_cmd, 100.0 * last.duty, state.residual_rms_rpm);
  } else {
    title += "   waiting for the stream";
  }
  if (state.recording) {
    title += fmt::format("   REC {} ({} rows)", printable_name(state.recording_path), state.recorded_rows);
  }
  if (state.lost_samples > 0) title += fmt::format("   lost {}", state.lost_samples);
  if (state.logging) title += "   LOG";
  if (!state.link_note.empty()) title = state.link_note + "   " + title;
  grid[0] = fit(title, width);

  const int duty_rows = 4;
  const int residual_rows = height >= 20 ? 3 : 0;
  const int speed_top = 2;
  const int speed_rows = height - speed_top - duty_rows - 5 - (residual_rows > 0 ? residual_rows + 1 : 0);
  const int left = 7;
  double lo = 0.0, hi = 0.0;
  bool any = false;
  for (const auto& s : samples) {
    for (double v : {s.rpm, s.rpm_model, s.rpm_cmd}) {
      if (!std::isfinite(v)) continue;
      lo = any ? std::min(lo, v) : v;
      hi = any ? std::max(hi, v) : v;
      any = true;
    }
  }
  if (any && hi - lo < 20.0) {
    lo -= 10.0;
    hi += 10.0;
  }
  grid[1] = fit(
      fmt::format("{:>{}}speed, rpm: * measured  o model  - command (last {:g} s)", "", left, state.span_s()), width);
  chart(grid, speed_top, speed_rows, left, width, samples, lo, hi,
        {{[](const ConsoleSample& s) { return s.rpm_cmd; }, '-'},
         {[](const ConsoleSample& s) { return s.rpm_model; }, 'o'},
         {[](const ConsoleSample& s) { return s.rpm; }, '*'}});
  int duty_top = speed_top + speed_rows + 1;
  if (residual_rows > 0) {
    double r_max = 5.0;
    for (const auto& s : samples) {
      if (std::isfinite(s.rpm - s.rpm_model)) r_max = std::max(r_max, std::abs(s.rpm - s.rpm_model));
    }
    grid[static_cast<std::size_t>(duty_top - 1)] =
        fit(fmt::format("{:>{}}residual, rpm: x measured - model", "", left), width);
    chart(grid, duty_top, residual_rows, left, width, samples, -r_max, r_max,
          {{[](const ConsoleSample& s) { return s.rpm - s.rpm_model; }, 'x'}});
    duty_top += residual_rows + 1;
  }
  grid[static_cast<std::size_t>(duty_top - 1)] = fit(fmt::format("{:>{}}duty, %", "", left), width);
  chart(grid, duty_top, duty_rows, left, width, samples, -100.0, 100.0,
        {{[](const ConsoleSample& s) { return 100.0 * s.duty; }, '#'}});
  const int bottom = duty_top + duty_rows;
  grid[static_cast<std::size_t>(bottom)] = fit(
      fmt::format("board: mode {}  rpm_cmd {}  duty {} %  kp {}  b0 {}  b1 {}  clutch {}  load {}  flags {}",
                  reg(state, "mode"), reg(state, "rpm_cmd"), reg(state, "duty"), reg(state, "kp"),
                  reg(state, "b0"), reg(state, "b1"), reg(state, "clutch"), reg(state, "load"),
                  reg(state, "flags")),
      width);
  grid[static_cast<std::size_t>(bottom + 1)] = fit(
      "keys: r rpm_cmd  d duty  m mode  k kp  s set  c clutch  l load  g/D RAM log  o load INI  w record  "
      "p pause  L log  ? help  q quit",
      width);
  grid[static_cast<std::size_t>(bottom + 2)] = fit(closed_loop_warning(state.registers), width);
  if (state.show_help) {
    const auto& help = console_key_help();
    for (int r = 1; r < bottom; ++r)
      grid[static_cast<std::size_t>(r)] = std::string(static_cast<std::size_t>(width), ' ');
    for (std::size_t k = 0; k < help.size() && static_cast<int>(k) + 2 < bottom; ++k) {
      grid[k + 2] = fit(help[k], width);
    }
  }
  grid[static_cast<std::size_t>(height - 1)] =
      fit(state.prompting() ? "> " + state.prompt_line() + "_" : state.status, width);
  return grid;
}

namespace {

/// The terminal in curses mode for as long as it lives; restored on every way out.
class Screen {
 public:
  Screen() {
    if (initscr() == nullptr) fail("console: cannot start the terminal screen");
    cbreak();
    noecho();
    keypad(stdscr, TRUE);
    nodelay(stdscr, TRUE);
    curs_set(0);
  }
  ~Screen() { endwin(); }
  Screen(const Screen&) = delete;
  Screen& operator=(const Screen&) = delete;

  void draw(const std::vector<std::string>& lines) {
    erase();
    for (std::size_t r = 0; r < lines.size(); ++r) mvaddnstr(static_cast<int>(r), 0, lines[r].c_str(), COLS);
    refresh();
  }
};

/// Runs the actions one at a time on a thread of its own, each as its subcommand would
/// (through this console, the port owner), and polls the registers when idle.
class Worker {
 public:
  Worker(LinkOptions link, double poll_s)
      : m_link(std::move(link)), m_poll_s(poll_s), m_thread([this] { loop(); }) {}
  ~Worker() {
    {
      const std::lock_guard lock(m_mutex);
      m_stop = true;
    }
    m_wake.notify_all();
    m_thread.join();
  }
  Worker(const Worker&) = delete;
  Worker& operator=(const Worker&) = delete;

  void post(ConsoleAction a) {
    {
      const std::lock_guard lock(m_mutex);
      m_queue.push_back(std::move(a));
    }
    m_wake.notify_all();
  }
  /// Moves the news (status, register values) into `state`; returns the status, if new. A poll
  /// error while the title already shows the link down (state.link_note) adds nothing and would
  /// overwrite the answer to what the user does meanwhile (a recording ended while the port is
  /// gone): it is dropped.
  std::string collect(ConsoleState& state) {
    const std::lock_guard lock(m_mutex);
    for (auto& [k, v] : m_registers) state.registers[k] = v;
    if (m_status.empty()) return {};
    if (std::exchange(m_status_is_poll, false) && !state.link_note.empty()) {
      m_status.clear();
      return {};
    }
    state.status = std::exchange(m_status, {});
    return state.status;
  }
  /// The board's configuration a record_csv action read (nullopt until it did, or when it
  /// failed: the reason is the status).
  std::optional<std::vector<std::pair<std::string, std::string>>> take_config(bool& failed) {
    const std::lock_guard lock(m_mutex);
    failed = std::exchange(m_config_failed, false);
    return std::exchange(m_config, std::nullopt);
  }

 private:
  void loop() {
    auto next_poll = std::chrono::steady_clock::now();
    for (;;) {
      std::optional<ConsoleAction> action;
      {
        std::unique_lock lock(m_mutex);
        m_wake.wait_until(lock, next_poll, [&] { return m_stop || !m_queue.empty(); });
        if (m_stop) return;
        if (!m_queue.empty()) {
          action = std::move(m_queue.front());
          m_queue.pop_front();
        }
      }
      if (action) {
        report(perform(*action));
      } else {
        poll();
        next_poll = std::chrono::steady_clock::now() +
                    std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                        std::chrono::duration<double>(m_poll_s));
      }
    }
  }

  void report(std::string text, bool poll_error = false) {
    const std::lock_guard lock(m_mutex);
    m_status = std::move(text);
    m_status_is_poll = poll_error;
  }

  std::string get(const std::string& name) {
    std::ostringstream out;
    run_get(m_link, {name}, out);
    std::string v = out.str();
    while (!v.empty() && (v.back() == '\n' || v.back() == ' ')) v.pop_back();
    return v;
  }

  void poll() {
    // board_config's registers (the port owner answers those from what it holds while the
    // stream runs) and the duty and flags.
    static const std::vector<std::string> names = [] {
      std::vector<std::string> n(config_register_names().begin(), config_register_names().end());
      n.emplace_back("duty");
      n.emplace_back("flags");
      return n;
    }();
    std::map<std::string, std::string> values;
    try {
      std::ostringstream out;
      run_get(m_link, names, out);
      std::istringstream lines(out.str());
      std::string line;
      for (const auto& n : names) {
        if (!std::getline(lines, line)) break;
        values[n] = line;
      }
    } catch (const Error& e) {
      // Said once per outage, not at every poll: a later poll error (a timeout, then "no such
      // port" once the port is gone) would overwrite the answer to what the user does meanwhile
      // (a recording ended while the port is gone).
      if (m_poll_error.empty()) {
        m_poll_error = fmt::format("polling the registers: {}", e.what());
        report(m_poll_error, true);
      }
      return;
    }
    m_poll_error.clear();
    const std::lock_guard lock(m_mutex);
    m_registers = std::move(values);
  }

  std::string perform(const ConsoleAction& a) {
    using Kind = ConsoleAction::Kind;
    std::ostringstream out;
    std::ostringstream err;
    Diagnostics diag(err, m_link.tool);
    try {
      switch (a.kind) {
        case Kind::set:
          if (a.name.empty() || a.value.empty()) return "set: give a register and a value";
          run_set(m_link, a.name, a.value, diag);
          return fmt::format("{} = {}{}", a.name, get(a.name),
                             err.str().empty() ? "" : "  (" + first_line(err.str()) + ")");
        case Kind::toggle_clutch: {
          const std::string now = get("clutch");
          const std::string next = now == "engaged" || now == "2" ? "disengaged" : "engaged";
          run_set(m_link, "clutch", next, diag);
          return fmt::format("clutch = {}", get("clutch"));
        }
        case Kind::toggle_load: {
          const std::string now = get("load");
          run_set(m_link, "load", now == "1" || now == "on" ? "0" : "1", diag);
          return fmt::format("load = {}", get("load"));
        }
        case Kind::record_log:
        case Kind::dump_log: {
          if (a.value.empty()) return "dump: give a file";
          DumpOptions d;
          d.record = a.kind == Kind::record_log;
          std::ostringstream csv;
          run_dump(m_link, d, csv, diag);
          std::ofstream file(a.value);
          file << csv.str();
          if (!file) return fmt::format("dump: cannot write {}", a.value);
          return fmt::format("RAM log written to {}", a.value);
        }
        case Kind::load_ini:
          if (a.value.empty()) return "load: give an INI file";
          run_load(m_link, a.value, out, diag);
          return fmt::format("loaded {}", a.value);
        case Kind::record_csv: {
          auto conn = connect(m_link);
          auto config = board_config(*conn);
          const std::lock_guard lock(m_mutex);
          m_config = std::move(config);
          return fmt::format("recording to {}", a.value);
        }
        case Kind::none:
        case Kind::session_log:
        case Kind::quit:
          return {};
      }
    } catch (const Error& e) {
      if (a.kind == Kind::record_csv) {
        const std::lock_guard lock(m_mutex);
        m_config_failed = true;
        return fmt::format("record: reading the board's configuration: {}", e.what());
      }
      return fmt::format("refused: {}", e.what());
    }
    return {};
  }

  static std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

  LinkOptions m_link;
  double m_poll_s;
  std::mutex m_mutex;
  std::condition_variable m_wake;
  std::deque<ConsoleAction> m_queue;
  std::string m_status;
  bool m_status_is_poll = false;  ///< m_status is a poll error
  std::string m_poll_error;  ///< the poll error said in this outage; the worker thread's alone
  std::map<std::string, std::string> m_registers;
  std::optional<std::vector<std::pair<std::string, std::string>>> m_config;
  bool m_config_failed = false;
  bool m_stop = false;
  std::thread m_thread;
};

/// The stream recording to a CSV file, in mcg-serial stream's format. Its header waits for
/// the board's configuration (read by the worker); the rows in between wait in `pending`. Its t
/// starts at 0 with its first row, as a capture's does; the header states the wall clock.
struct Recording {
  std::ofstream file;
  std::optional<table::Writer> writer;
  bool header_written = false;
  std::vector<StreamRow> pending;
  double started_unix_s = 0.0;  ///< the wall clock when the recording began
  std::optional<double> t0_s;   ///< the console's t of its first row: the file's t = 0
};

/// What an action asks, for the session log: "set rpm_cmd 450", "load pi.ini", ...
std::string describe(const ConsoleAction& a) {
  using Kind = ConsoleAction::Kind;
  switch (a.kind) {
    case Kind::set:
      return fmt::format("set {} {}", a.name, a.value);
    case Kind::toggle_clutch:
      return "toggle the clutch";
    case Kind::toggle_load:
      return "toggle the load";
    case Kind::record_log:
      return fmt::format("record the RAM log and dump it to {}", a.value);
    case Kind::dump_log:
      return fmt::format("dump the RAM log to {}", a.value);
    case Kind::load_ini:
      return fmt::format("load {}", a.value);
    default:
      return {};
  }
}

double unix_now_s() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

/// "2026-11-26T23:15:02.123Z": the wall clock `unix_s`, UTC, to the millisecond.
std::string utc_text(double unix_s) {
  const auto whole = static_cast<std::time_t>(std::floor(unix_s));
  const auto ms = std::clamp(static_cast<int>(std::floor((unix_s - std::floor(unix_s)) * 1e3)), 0, 999);
  std::tm utc{};
  gmtime_r(&whole, &utc);
  return fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}.{:03}Z", utc.tm_year + 1900, utc.tm_mon + 1,
                     utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec, ms);
}

}  // namespace

std::string session_log_line(double unix_s, std::string_view text) {
  return fmt::format("{} {}", utc_text(unix_s), text);
}

int run_console(const LinkOptions& link, const ConsoleOptions& options) {
  if (::isatty(STDIN_FILENO) != 1 || ::isatty(STDOUT_FILENO) != 1) {
    fail("console: stdin and stdout must be a terminal (use 'stream' to capture data)");
  }
  constexpr int k_window_samples = 4;  // the board's 16 ms rpm window
  constexpr double k_sample_s = MCG_STREAM_PERIOD_MS * 1e-3;
  /// No stream block for this long is a stall the screen reports (blocks come every 64 ms).
  constexpr double k_stall_s = 2.0;
  /// While the port is gone or silent, the console tries to reach it again this often.
  constexpr double k_retry_s = 0.5;
  const Rig rig = load_rig(options.rig);
  model::Model model;
  if (!options.rig.configs.empty()) model = model::load_model(options.rig.configs, {});
  std::ofstream session_log;
  ConsoleState state(options.span_s);
  state.title = link.tool + " console";
  const auto log = [&](std::string_view text) {
    if (!session_log.is_open() || text.empty()) return;
    session_log << session_log_line(unix_now_s(), text) << '\n' << std::flush;
  };
  const auto open_log = [&](const std::string& path) {
    session_log.open(path, std::ios::app);
    if (!session_log) return false;
    state.logging = true;
    log(fmt::format("session log of {} on {}", state.title, link.port));
    return true;
  };
  if (!options.log_path.empty() && !open_log(options.log_path)) {
    fail("console: --log: cannot open {}", quote(options.log_path));
  }
  auto c = connect(link, Hold::Serve);
  const InterruptGuard guard;
  c->session->write(require_register("stream"), 1);
  log(fmt::format("connected: {}", c->board_text()));

  StreamAssembler assembler(k_window_samples);
  std::optional<model::Plant> plant;
  Recording rec;
  std::size_t recorded = 0;
  const auto write_row = [&](const StreamRow& r) {
    if (!rec.writer) return;
    if (!rec.t0_s) rec.t0_s = r.t_s;
    if (!rec.header_written) {
      rec.pending.push_back(r);
      return;
    }
    StreamRow from_start = r;
    from_start.t_s -= *rec.t0_s;
    write_stream_row(*rec.writer, from_start, rig);
    ++recorded;
  };
  auto stop_recording = [&] {
    if (!rec.writer) return;
    rec.writer->finish();
    rec.writer.reset();
    rec.file.close();
    state.status = fmt::format("recorded {} rows to {}", recorded, printable_name(state.recording_path));
    state.recording = false;
    log(state.status);
  };
  using Clock = std::chrono::steady_clock;
  const auto since = [](Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
  };
  const auto start = Clock::now();
  auto last_block = start;
  auto quiet_from = start;  // the last block, or the moment the port came back
  auto next_draw = start;
  auto next_retry = start;
  std::string ended_by;
  std::string last_warning;
  {
    Worker worker(link, options.poll_s);
    Screen screen;
    for (;;) {
      // The stream first: every block that has arrived, then the keys, then the screen.
      try {
        if (c) {
          while (auto f = c->session->receive(0.01)) {
            if (f->cmd != MCG_MSG_STREAM) continue;
            const double gap = since(last_block);
            last_block = Clock::now();
            quiet_from = last_block;
            if (!assembler.push(f->payload, gap)) continue;
            for (const StreamRow& r : assembler.rows()) {
              model::Drive drive;
              drive.v_V = std::isfinite(r.duty) ? r.duty * rig.supply_V : 0.0;
              drive.clutch = std::isfinite(r.clutch) ? static_cast<int>(r.clutch) : 2;
              drive.r_load_ohm = r.load == 1.0 ? rig.r_load_ohm : model::k_open_circuit;
              // The model starts as the console found the rig (and again after a break): at
              // the first measured speed.
              if (!std::isfinite(r.duty)) plant.reset();
              if (!plant && std::isfinite(r.rpm)) {
                plant.emplace(model, model::SimOptions{}, drive.clutch);
                plant->start_at(rad_s_from_rpm(r.rpm));
              }
              double rpm_model = std::numeric_limits<double>::quiet_NaN();
              if (plant) {
                plant->step(k_sample_s, drive);
                rpm_model = rpm_from_rad_s(plant->state().omega_rad_s);
              }
              state.add({r.t_s, r.rpm, rpm_model, r.rpm_cmd, r.duty});
              write_row(r);
            }
            if (rec.writer && rec.header_written) rec.writer->finish();
            state.recorded_rows = recorded;
            state.lost_samples = assembler.lost_samples();
            if (!state.link_note.empty()) {
              state.link_note.clear();
              state.status = "stream data again";
              log(state.status);
            }
            if (Clock::now() >= next_draw) break;
          }
        } else if (Clock::now() >= next_retry) {
          // The port vanished: reach it again (as its owner, or through a new one).
          next_retry = Clock::now() + std::chrono::milliseconds(static_cast<int>(k_retry_s * 1e3));
          try {
            auto again = connect(link, Hold::Serve);
            again->session->write(require_register("stream"), 1);
            c = std::move(again);
            assembler.restart();
            quiet_from = Clock::now();
            state.link_note = "PORT BACK";
            log(fmt::format("{}: the port is back", link.port));
          } catch (const Error&) {
            // Not back yet.
          }
        }
        if (c && since(quiet_from) > k_stall_s && Clock::now() >= next_retry) {
          // A board that reset stops its stream: ask for it again now and then.
          next_retry = Clock::now() + std::chrono::milliseconds(static_cast<int>(k_retry_s * 1e3));
          const std::string note =
              fmt::format("{}: no stream data for {:.0f} s", link.port, since(last_block));
          if (state.link_note != note) {
            if (state.link_note.empty()) log(note);
            state.link_note = note;
          }
          try {
            c->session->write(require_register("stream"), 1);
            assembler.restart();
            quiet_from = Clock::now();
          } catch (const PortVanished&) {
            throw;
          } catch (const Error&) {
            // Still silent.
          }
        }
      } catch (const PortVanished&) {
        c.reset();
        state.link_note = fmt::format("{}: THE PORT VANISHED, waiting for it (q quits)", link.port);
        log(state.link_note);
      }
      if (rec.writer && !rec.header_written && c) {
        bool failed = false;
        if (auto config = worker.take_config(failed)) {
          rec.writer->meta("t0", fmt::format("the first row streamed after the recording began at {} (wall "
                                             "clock, UTC)",
                                             utc_text(rec.started_unix_s)));
          write_stream_header(*rec.writer, *c, link, k_window_samples, rig, *config);
          rec.header_written = true;
          for (const StreamRow& r : rec.pending) write_row(r);
          rec.pending.clear();
          rec.writer->finish();
        } else if (failed) {
          rec.writer.reset();
          rec.file.close();
          std::remove(state.recording_path.c_str());
          state.recording = false;
        }
      }
      for (int ch = getch(); ch != ERR; ch = getch()) {
        const bool was_prompting = state.prompting();
        const ConsoleAction a = state.key(ch);
        if (!was_prompting && (ch == 'p' || ch == '?')) log(ch == 'p' ? state.status : "key ?");
        if (a.kind == ConsoleAction::Kind::quit) {
          ended_by = "quit";
          break;
        }
        if (a.kind == ConsoleAction::Kind::session_log) {
          if (state.logging) {
            log("session log ends");
            session_log.close();
            state.logging = false;
            state.status = "session log closed";
          } else if (a.value.empty()) {
            state.status = "session log: give a file";
          } else if (!open_log(a.value)) {
            state.status = fmt::format("session log: cannot open {}", a.value);
          } else {
            state.status = fmt::format("session log to {}", a.value);
          }
        } else if (a.kind == ConsoleAction::Kind::record_csv) {
          if (rec.writer) {
            stop_recording();
          } else if (a.value.empty()) {
            state.status = "record: give a file";
          } else if (!c) {
            state.status = "record: the port is gone";
          } else {
            rec.file.open(a.value);
            if (!rec.file) {
              state.status = fmt::format("record: cannot open {}", a.value);
            } else {
              // The header states the registers as they are now: the worker reads them while
              // the rows wait, so neither the stream nor the screen waits for the board.
              rec.writer.emplace(rec.file);
              rec.header_written = false;
              rec.pending.clear();
              rec.started_unix_s = unix_now_s();
              rec.t0_s.reset();
              recorded = 0;
              state.recording = true;
              state.recording_path = a.value;
              state.status = fmt::format("recording to {}", a.value);
              worker.post(a);
              log(fmt::format("recording to {}", a.value));
            }
          }
        } else if (a.kind != ConsoleAction::Kind::none) {
          state.status = "...";
          worker.post(a);
          log(describe(a));
        }
      }
      if (!ended_by.empty() || InterruptGuard::interrupted()) break;
      if (options.seconds > 0.0 && since(start) >= options.seconds) break;
      if (Clock::now() >= next_draw) {
        log(worker.collect(state));
        const std::string warning = closed_loop_warning(state.registers);
        if (warning != last_warning) log(warning);
        last_warning = warning;
        screen.draw(render_console(state, COLS, LINES));
        next_draw = Clock::now() + std::chrono::milliseconds(100);
      }
      if (!c) ::usleep(10000);
    }
  }
  stop_recording();
  log("session ends");
  if (c) {
    try {
      c->session->write(require_register("stream"), 0);
    } catch (const Error&) {
      // Leaving: a board that does not confirm the stop changes nothing here.
    }
  }
  return 0;
}

}  // namespace mcg::link
