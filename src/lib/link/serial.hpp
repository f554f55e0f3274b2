// mcg-serial: the board from the terminal (see man/mcg-serial.1). One function per subcommand.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "common/diagnostics.hpp"
#include "config/ini.hpp"
#include "link/capture_meta.hpp"  // RigOptions
#include "link/registers.hpp"
#include "link/session.hpp"  // SeqEntry
#include "table/table.hpp"

namespace mcg::link {

/// Options every subcommand that talks to the board shares.
struct LinkOptions {
  std::string port;              ///< -p/--port
  int baud = 9600;               ///< --baud
  double timeout_s = 0.3;        ///< --timeout: wait for each answer
  int attempts = 3;              ///< --tries: attempts per request
  std::string tool;              ///< the tool's name, for the provenance its outputs record
};

/// Exit status of a capture that lost samples (without --allow-loss).
inline constexpr int k_exit_lost_samples = 3;

/// list: every serial port with its description, "PATH<TAB>DESCRIPTION" per line, then the
/// emulated boards running (mcg-sim --board, emulated_ports()).
void run_list(std::ostream& out);

/// get NAME...: each register's value in engineering units, one per line. Without names:
/// every register as an INI [board] section (read-only ones and commit as comments), which load reads.
void run_get(const LinkOptions& link, const std::vector<std::string>& names, std::ostream& out);

/// set NAME VALUE: writes one register in engineering units and reads it back. A value the
/// register cannot hold exactly is rounded to its resolution (a note on `diag` says so); a
/// board that holds something else after the write is an error. A register of the controller's
/// set (RegisterInfo::staged) is staged onto the running set and committed at once: the loop
/// changes at one tick, and a set the board refuses (a closed-loop mode with every gain zero)
/// changes nothing and fails with the board's reason.
void run_set(const LinkOptions& link, const std::string& name, const std::string& value, Diagnostics& diag);

/// load FILE.ini: writes the [board] section (register = value, as get prints it) or the
/// [controller] fixed-point section of mcg-design (docs/formats.md), verifies each register
/// and prints what the board holds as a [board] section. The controller's registers are staged
/// and committed once, so the loop swaps controllers at one tick, bumpless; then the rest.
void run_load(const LinkOptions& link, const std::string& path, std::ostream& out, Diagnostics& diag);

/// One register write of load FILE.ini and the file:line it came from.
struct LoadWrite {
  const RegisterInfo* reg;
  double value;
  std::string origin;
};
using LoadPlan = std::vector<LoadWrite>;
/// The writes of load FILE.ini ([board] registers, the [controller] section) without the board,
/// in the order they are written. Throws mcg::Error naming file:line.
LoadPlan load_plan(const config::Ini& ini, const std::string& path);

struct StreamOptions {
  double seconds = 0.0;            ///< stop after this much stream time (0: see samples)
  std::int64_t samples = 0;        ///< stop after this many samples (0 with seconds 0: until Ctrl-C)
  bool allow_loss = false;         ///< exit 0 even when samples were lost
  double window_s = 0.016;         ///< rpm estimator window, s (a multiple of the 4 ms sample)
  double idle_timeout_s = 1.0;     ///< no stream block for this long is an error
  RigOptions rig;                  ///< supply and load resistor: v and r_load of the rows
  std::string then;                ///< "", "play", "loop" (the loaded sequence) or "excite" (exc_run)
  double reconnect_wait_s = 0.0;   ///< > 0: when the port vanishes or the stream stops, wait this long
                                   ///< for it to come back and go on after a break row (0: an error)
};
/// stream: turns the board's stream on, writes CSV rows (t, rpm, counts, duty, v, rpm_cmd,
/// clutch, r_load; mcg-csv(5)) as the blocks arrive (flushed per block), turns it off at the end.
/// Sequence gaps count as lost samples: reported on `diag`, exit status k_exit_lost_samples unless
/// allow_loss.
/// SIGINT ends the capture cleanly. Returns the exit status.
int run_stream(const LinkOptions& link, const StreamOptions& options, std::ostream& out, Diagnostics& diag);

struct DumpOptions {
  bool record = false;       ///< start a recording first and wait until the log is full
  int interval_ms = 0;       ///< with record: set log_interval first (0: keep the board's)
};
/// dump: the RAM log as CSV (t, rpm, counts), t = (i + 1) interval: point i holds the pulses
/// counted over (t - interval, t] after the recording started.
void run_dump(const LinkOptions& link, const DumpOptions& options, std::ostream& out, Diagnostics& diag);

struct SendOptions {
  std::string path;         ///< CSV: t and one column per register to change
  std::string then;         ///< "", "play" or "loop": start playback after loading
};
/// The sequence of send FILE.csv without the board: an entry wherever a register column
/// changes, gains in `frac_bits` fixed point, and a commit after a row's changes of the
/// controller's registers. Throws mcg::Error naming file:line.
std::vector<SeqEntry> send_plan(const table::Table& tbl, int frac_bits);

/// send FILE.csv: turns a table of register values over time into the board's command
/// sequence (an entry wherever a register column changes) and loads it into the board's RAM.
void run_send(const LinkOptions& link, const SendOptions& options, std::ostream& out);

struct ServeOptions {
  double seconds = 0.0;      ///< 0: until Ctrl-C
};
/// serve: holds the port and serves every other mcg-serial command on it (PortOwner) until
/// Ctrl-C or `seconds`; fails when another mcg-serial already holds it, or when the port vanishes.
void run_serve(const LinkOptions& link, const ServeOptions& options);

struct MonitorOptions {
  double seconds = 0.0;      ///< 0: until Ctrl-C
  double period_s = 0.2;     ///< redraw period
};
/// monitor: one redrawn line of live values; stdout must be a terminal.
void run_monitor(const LinkOptions& link, const MonitorOptions& options, std::ostream& out);

}  // namespace mcg::link
