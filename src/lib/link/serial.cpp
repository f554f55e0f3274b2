// mcg-serial subcommands: list, get, set, load, dump, send, monitor (stream is in stream.cpp).
#include "link/serial.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ostream>

#include <fmt/format.h>

#include "common/error.hpp"     // mcg::fail
#include "common/quote.hpp"
#include "common/tool.hpp"
#include "config/ini.hpp"       // Ini
#include "mcg_protocol.h"       // MCG_MODE_OPEN
#include "link/capture_meta.hpp"  // board_config, k_encoder_text
#include "link/connection.hpp"  // Connection
#include "link/interrupt.hpp"   // InterruptGuard
#include "link/owner.hpp"       // PortOwner, connect_owner, open_shared_port
#include "mcg/version.hpp"      // k_version
#include "measurement/measurement.hpp"  // CountEstimator, format_rpm_estimator
#include "table/table.hpp"      // Writer, read_path

namespace mcg::link {

Connection::Connection() = default;
Connection::~Connection() = default;

std::unique_ptr<Connection> connect(const LinkOptions& link, Hold hold) {
  for (int attempt = 0;; ++attempt) {
    auto c = std::make_unique<Connection>();
    bool through_owner = false;
    if (auto owner_line = connect_owner(link.port)) {
      c->port = std::move(owner_line);
      through_owner = true;
    } else {
      auto port = open_shared_port(link.port, link.baud);
      if (hold == Hold::Serve && port->poll_fd() >= 0) {
        c->owner = std::make_unique<PortOwner>(std::move(port));
        c->port = c->owner->local_client();
      } else {
        c->port = std::move(port);
      }
    }
    SessionOptions so;
    so.reply_timeout_s = link.timeout_s;
    so.attempts = link.attempts;
    so.tool = link.tool;
    if (through_owner || c->owner) so.read_many_chunk = MCG_READ_MANY_MAX;
    c->session = std::make_unique<Session>(*c->port, so);
    try {
      c->version = c->session->hello();
    } catch (const PortVanished&) {
      // An owner that ended as this process came: once more, on the port or its next owner.
      if (!through_owner || attempt > 0) throw;
      continue;
    }
    return c;
  }
}

int Connection::frac_bits() {
  if (!m_frac_bits) m_frac_bits = session->read(require_register("coef_frac"));
  return *m_frac_bits;
}

std::string Connection::board_text() const {
  return fmt::format("{} firmware {}.{}.{}, protocol {}", board_name(version.board), version.major, version.minor,
                     version.patch, version.protocol);
}

namespace {

constexpr double k_pulses_to_rev = 1.0 / MCG_COUNTS_PER_REV;
/// How long a writer waits for another client's staged set to be committed: a load takes under
/// 2 s through a streaming port, and the owner discards a set silent for k_stage_idle_s.
constexpr double k_stage_wait_s = k_stage_idle_s + 1.0;

/// Writes `value` (engineering units) into `reg` and checks what the board holds: for a staged
/// register the shadow value its answer reports, else the register read back. Returns the raw value
/// held. Notes a rounded value on `diag`; throws when the board holds something else, and names the
/// mode when the board refuses a duty its controller owns.
/// A sequence plays on the board that owns the controller's shadow set (it has entries of it):
/// the board refuses every other writer's staging until the sequence stops.
bool sequence_owns_set(Connection& c) {
  return (static_cast<unsigned>(c.session->read(require_register("flags"))) & MCG_FLAG_SEQ_SET) != 0;
}

[[noreturn]] void fail_sequence_owns_set(Connection& c, std::string_view what) {
  fail(
      "{}: {}: a playing sequence owns the controller's set until it stops (seq_state 0); nothing was "
      "written",
      c.port->name(), what);
}

std::int16_t write_verified(Connection& c, const RegisterInfo& reg, double value, std::string_view where,
                            Diagnostics& diag) {
  if (!reg.writable) fail("{}: {} is read-only", where, reg.name);
  const int frac = reg.unit == Unit::Gain ? c.frac_bits() : 0;
  const std::int16_t raw = to_raw(reg, value, frac);
  std::int16_t held = 0;
  try {
    held = c.session->write(reg, raw);
  } catch (const Refused& e) {
    if (e.status() == MCG_ST_BUSY && reg.staged) {
      if (sequence_owns_set(c)) fail_sequence_owns_set(c, fmt::format("writing {}", reg.name));
      fail(
          "{}: writing {}: the port's owner discarded this writer's staged set (silent over {} s); "
          "nothing was committed",
          c.port->name(), reg.name, k_stage_idle_s);
    }
    if (e.status() != MCG_ST_OWNED) throw;
    const RegisterInfo& mode = require_register("mode");
    fail("{}: writing {}: the controller owns {} in mode {}; set mode open first", c.port->name(), reg.name,
         reg.name, format_value(mode, c.session->read(mode), 0));
  }
  if (!reg.staged) held = c.session->read(reg);
  if (held != raw) {
    fail("{}: {}: the board holds {} after writing {}", c.port->name(), reg.name, format_value(reg, held, frac),
         format_value(reg, raw, frac));
  }
  if (reg.name == "coef_frac") c.set_frac_bits(held);  // the staged gains that follow are in this format
  const double held_value = to_engineering(reg, held, frac);
  if (held_value != value && reg.unit != Unit::Mode && reg.unit != Unit::SeqState) {
    diag.note(fmt::format("{}: {} is held as {} (the register's resolution)", reg.name,
                          config::format_number(value), format_value(reg, held, frac)));
  }
  return held;
}

/// Empties the board's shadow set (a copy of the active controller again), so that what follows
/// stages onto the controller that runs and nothing another writer left half-done.
/// Through a shared port another client may be staging a set of its own: its writes and commit
/// come first (the owner answers BUSY until it commits), for up to k_stage_wait_s.
void discard_staged(Connection& c) {
  const RegisterInfo& commit = require_register("commit");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(k_stage_wait_s);
  for (;;) {
    try {
      c.session->write(commit, 0);
      break;
    } catch (const Refused& e) {
      if (e.status() != MCG_ST_BUSY) throw;
      if (sequence_owns_set(c)) fail_sequence_owns_set(c, "staging a controller");
      if (std::chrono::steady_clock::now() > deadline) {
        fail(
            "{}: another client of the port has been staging a controller for {} s without committing it; "
            "nothing was written",
            c.port->name(), k_stage_wait_s);
      }
      ::usleep(50'000);
    }
  }
  c.forget_frac_bits();
}

/// Makes the staged set the board's controller, at one tick, and checks that the board runs
/// `staged` (register, raw value written). A refusal is one line naming the board's reason.
void commit_staged(Connection& c, std::span<const std::pair<const RegisterInfo*, std::int16_t>> staged,
                   std::string_view what) {
  try {
    c.session->write(require_register("commit"), 1);
  } catch (const Refused& e) {
    fail("{}: {}: refused ({}): {}", c.port->name(), what, status_name(e.status()), status_text(e.status()));
  }
  c.forget_frac_bits();
  for (const auto& [reg, raw] : staged) {
    const int frac = reg->unit == Unit::Gain ? c.frac_bits() : 0;
    const std::int16_t held = c.session->read(*reg);
    if (held != raw) {
      fail("{}: {}: the board runs {} = {} after the commit, not {} (another writer?)", c.port->name(), what,
           reg->name, format_value(*reg, held, frac), format_value(*reg, raw, frac));
    }
  }
}

/// The order load writes registers in: the controller's set (staged, committed at once), the
/// fixed-point format before the gains it scales; then the rest, sequence playback and the stream last.
int load_rank(const RegisterInfo& reg) {
  if (reg.name == "coef_frac") return 0;
  if (reg.staged) return 1;
  if (reg.name == "stream" || reg.name == "seq_state") return 3;
  return 2;
}

void print_board_section(Connection& c, std::span<const RegisterInfo* const> regs, std::ostream& out) {
  out << "[board]\n";
  const std::vector<std::int16_t> values = c.session->read_many(regs);
  for (std::size_t k = 0; k < regs.size(); ++k) {
    const RegisterInfo* reg = regs[k];
    const int frac = reg->unit == Unit::Gain ? c.frac_bits() : 0;
    const std::int16_t raw = values[k];
    const std::string_view comment = reg->doc;
    if (reg->id == MCG_REG_COMMIT) {
      out << fmt::format("; {} = {}  (an action, not a setting) {}\n", reg->name,
                         format_value(*reg, raw, frac), comment);
    } else if (reg->writable) {
      out << fmt::format("{} = {}  ; {}\n", reg->name, format_value(*reg, raw, frac), comment);
    } else {
      out << fmt::format("; {} = {}  (read-only) {}\n", reg->name, format_value(*reg, raw, frac), comment);
    }
  }
}

}  // namespace

void run_list(std::ostream& out) {
  for (const auto& p : list_ports()) out << p.name << '\t' << p.description << '\n';
  for (const auto& p : emulated_ports()) out << p.name << '\t' << p.description << '\n';
}

void run_get(const LinkOptions& link, const std::vector<std::string>& names, std::ostream& out) {
  std::vector<const RegisterInfo*> regs;
  for (const auto& name : names) regs.push_back(&require_register(name));
  auto c = connect(link);
  if (names.empty()) {
    for (const auto& reg : registers()) regs.push_back(&reg);
    out << fmt::format("; {} get: {} on {}\n", link.tool, c->board_text(), printable_name(link.port));
    print_board_section(*c, regs, out);
    return;
  }
  for (const RegisterInfo* reg : regs) {
    const int frac = reg->unit == Unit::Gain ? c->frac_bits() : 0;
    out << format_value(*reg, c->session->read(*reg), frac) << '\n';
  }
}

void run_set(const LinkOptions& link, const std::string& name, const std::string& value, Diagnostics& diag) {
  const RegisterInfo& reg = require_register(name);
  if (!reg.writable) fail("set: {} is read-only", reg.name);
  const double v = parse_value(reg, value, "set");
  if (reg.unit != Unit::Gain) to_raw(reg, v, 0);  // range check before touching the port
  auto c = connect(link);
  if (reg.id == MCG_REG_COMMIT) {  // an action: what others staged is committed (1) or dropped (0)
    if (v == 0) {
      discard_staged(*c);
    } else {
      commit_staged(*c, {}, "committing what is staged");
    }
    return;
  }
  if (!reg.staged) {
    write_verified(*c, reg, v, "set", diag);
    return;
  }
  // One register of the controller's set: staged onto the running set and committed, so the loop
  // changes at one tick and a set the board refuses changes nothing.
  discard_staged(*c);
  const std::int16_t raw = write_verified(*c, reg, v, "set", diag);
  const std::pair<const RegisterInfo*, std::int16_t> staged[] = {{&reg, raw}};
  commit_staged(*c, staged, fmt::format("committing {} {}", reg.name, value));
}

LoadPlan load_plan(const config::Ini& ini, const std::string& path) {
  std::vector<std::pair<const RegisterInfo*, double>> writes;
  std::vector<std::string> origins;
  const auto add = [&](const RegisterInfo& reg, double value, const std::string& origin) {
    for (auto& w : writes) {
      if (w.first == &reg) {
        w.second = value;
        return;
      }
    }
    writes.emplace_back(&reg, value);
    origins.push_back(origin);
  };
  for (const auto* e : ini.entries("board")) {
    const RegisterInfo* reg = find_register(e->key);
    if (reg == nullptr) ini.reject("board", e->key, "not a register of the board");
    if (!reg->writable) ini.reject("board", e->key, "read-only register");
    if (reg->id == MCG_REG_COMMIT) {
      ini.reject("board", e->key, "an action, not a setting (load commits itself)");
    }
    add(*reg, parse_value(*reg, e->value, e->origin), e->origin);
  }
  for (const auto& [reg, value] : controller_registers(ini)) add(*reg, value, path);
  // In a closed-loop mode `duty` is the controller's output, which `get` saves but the board
  // takes only in open loop: it is restored by the mode, not written.
  const auto mode = std::find_if(writes.begin(), writes.end(), [](const auto& w) { return w.first->name == "mode"; });
  if (mode != writes.end() && mode->second != MCG_MODE_OPEN) {
    const auto duty = std::find_if(writes.begin(), writes.end(), [](const auto& w) { return w.first->name == "duty"; });
    if (duty != writes.end()) {
      origins.erase(origins.begin() + (duty - writes.begin()));
      writes.erase(duty);
    }
  }
  if (writes.empty()) fail("{}: no [board] or [controller] section with registers to load", path);
  std::vector<std::size_t> order(writes.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return load_rank(*writes[a].first) < load_rank(*writes[b].first); });

  LoadPlan plan;
  for (const std::size_t i : order) plan.push_back({writes[i].first, writes[i].second, origins[i]});
  return plan;
}

void run_load(const LinkOptions& link, const std::string& path, std::ostream& out, Diagnostics& diag) {
  const LoadPlan plan = load_plan(config::Ini::load(path), input_name(path));
  auto c = connect(link);
  // The controller's set is staged whole and committed once: the loop runs the old controller up
  // to one tick and the new one, bumpless, from the next; the board checks the set as a whole
  // (duty_min <= duty_max, gains for a closed-loop mode) and a refused set changes nothing. The
  // rest (an open-loop duty within the new limits, the command, the outputs) follows.
  discard_staged(*c);
  std::vector<std::pair<const RegisterInfo*, std::int16_t>> staged;
  for (const LoadWrite& w : plan) {
    if (w.reg->staged) staged.emplace_back(w.reg, write_verified(*c, *w.reg, w.value, w.origin, diag));
  }
  if (!staged.empty()) commit_staged(*c, staged, fmt::format("committing the controller of {}", path));
  for (const LoadWrite& w : plan) {
    if (!w.reg->staged) write_verified(*c, *w.reg, w.value, w.origin, diag);
  }

  std::vector<const RegisterInfo*> regs;
  for (const LoadWrite& w : plan) regs.push_back(w.reg);
  out << fmt::format("; {} load {}: {} on {}, every register read back\n", link.tool, input_name(path),
                     c->board_text(), printable_name(link.port));
  print_board_section(*c, regs, out);
}

void run_dump(const LinkOptions& link, const DumpOptions& options, std::ostream& out, Diagnostics& diag) {
  auto c = connect(link);
  Session& s = *c->session;
  if (options.record) {
    if (options.interval_ms != 0) {
      write_verified(*c, require_register("log_interval"), options.interval_ms, "--interval", diag);
    }
    const int interval_ms = s.read(require_register("log_interval"));
    s.request(MCG_CMD_LOG_START, {}, "starting the log");
    const InterruptGuard guard;
    const double expected_s = MCG_LOG_POINTS * 1e-3 * interval_ms;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(expected_s + 2.0);
    const RegisterInfo& flags = require_register("flags");
    for (;;) {
      if (InterruptGuard::interrupted()) fail("dump: interrupted while recording");
      const auto f = static_cast<unsigned>(s.read(flags));
      if ((f & MCG_FLAG_LOG_FULL) != 0 && (f & MCG_FLAG_LOGGING) == 0) break;
      if (std::chrono::steady_clock::now() > deadline) {
        fail("{}: the log did not fill within {} s", link.port, config::format_number(expected_s + 2.0));
      }
      s.receive(std::min(0.1, expected_s / 4.0 + 0.01));
    }
  }
  const LogDump dump = s.dump_log();
  if (dump.counts.empty()) {
    fail("{}: the RAM log is empty (record one with 'dump --record', or with the keypad)", link.port);
  }
  const double interval_s = dump.interval_ms * 1e-3;
  table::Writer w(out);
  w.meta("source", fmt::format("{} {} dump", link.tool, k_version));
  w.meta("board", c->board_text());
  w.meta("port", printable_name(link.port));
  w.meta("sample_period", config::format_number(interval_s));
  measurement::CountEstimator est;
  est.window_s = interval_s;
  est.counts_per_rev = MCG_COUNTS_PER_REV;
  w.meta("rpm_estimator", measurement::format_rpm_estimator(est));
  w.meta("encoder", k_encoder_text);
  w.meta("timing",
         "counts and rpm over (t - sample_period, t]; t = 0 when the recording started; speed signed with the "
         "direction of the last non-zero drive");
  w.meta("board_config", [&] {
    std::string text;
    for (const auto& [name, value] : board_config(*c)) text += fmt::format("{}{}={}", text.empty() ? "" : " ", name, value);
    return text;
  }());
  w.header({"t", "rpm", "counts"});
  for (std::size_t i = 0; i < dump.counts.size(); ++i) {
    // Points are i16: pulses signed with the direction of the last non-zero drive.
    const double counts = static_cast<std::int16_t>(dump.counts[i]);
    w.row({static_cast<double>(i + 1) * interval_s, counts * k_pulses_to_rev / interval_s * 60.0, counts});
  }
  w.finish();
}

std::vector<SeqEntry> send_plan(const table::Table& tbl, int frac_bits) {
  const std::string src = tbl.source;
  table::require_increasing(tbl, "t");
  const auto& t = tbl.col("t");
  std::vector<std::pair<const RegisterInfo*, const std::vector<double>*>> cols;
  for (std::size_t k = 0; k < tbl.names.size(); ++k) {
    if (tbl.names[k] == "t") continue;
    const RegisterInfo* reg = find_register(tbl.names[k]);
    if (reg == nullptr || reg->name != tbl.names[k]) continue;
    if (!reg->writable) fail("{}: column {}: read-only register", src, quote(tbl.names[k]));
    cols.emplace_back(reg, &tbl.columns[k]);
  }
  if (cols.empty()) fail("{}: no column names a writable register (e.g. rpm_cmd, duty, mode)", src);
  if (!tbl.rows()) fail("{}: no rows", src);

  std::vector<SeqEntry> entries;
  std::vector<double> last(cols.size(), std::nan(""));
  std::int64_t prev_ms = 0;
  bool staged_in_row = false;
  for (std::size_t row = 0; row < tbl.rows(); ++row) {
    for (std::size_t k = 0; k < cols.size(); ++k) {
      const RegisterInfo& reg = *cols[k].first;
      const double v = (*cols[k].second)[row];
      if (std::isnan(v) || v == last[k]) continue;
      last[k] = v;
      if (t[row] < 0.0) fail("{}:{}: t = {} s: a sequence starts at t = 0", src, tbl.line_of(row), t[row]);
      // Bounded before the conversion: llround of a huge or infinite t has no defined result.
      if (!(t[row] * 1e3 - static_cast<double>(prev_ms) <= 65535.5)) {
        fail("{}:{}: t = {} s: more than 65535 ms after the previous change; the board waits at most 65535 ms",
             src, tbl.line_of(row), t[row]);
      }
      const auto at_ms = static_cast<std::int64_t>(std::llround(t[row] * 1e3));
      if (at_ms - prev_ms > 0xFFFF) {
        fail("{}:{}: {} ms after the previous change; the board waits at most 65535 ms", src, tbl.line_of(row),
             at_ms - prev_ms);
      }
      // The data contract's duty is a fraction of full scale; the register's unit is %.
      const double value = reg.unit == Unit::Percent ? v * 100.0 : v;
      const int frac = reg.unit == Unit::Gain ? frac_bits : 0;
      std::int16_t raw = 0;
      try {
        raw = to_raw(reg, value, frac);
      } catch (const Error& e) {
        fail("{}:{}: {}", src, tbl.line_of(row), e.what());
      }
      entries.push_back({static_cast<std::uint16_t>(at_ms - prev_ms), reg.id, raw});
      prev_ms = at_ms;
      staged_in_row = staged_in_row || reg.staged;
    }
    // The controller registers a row changes are staged; one commit right after them makes them
    // act together, on the same tick.
    if (staged_in_row) entries.push_back({0, MCG_REG_COMMIT, 1});
    staged_in_row = false;
    if (entries.size() > MCG_SEQ_MAX) {
      fail("{}:{}: more than {} register changes; the board's sequence holds {}", src, tbl.line_of(row),
           MCG_SEQ_MAX, MCG_SEQ_MAX);
    }
  }
  return entries;
}

void run_send(const LinkOptions& link, const SendOptions& options, std::ostream& out) {
  const table::Table tbl = table::read_path(options.path);
  send_plan(tbl, 0);  // every input error before the port is opened
  auto c = connect(link);
  const std::vector<SeqEntry> entries = send_plan(tbl, c->frac_bits());
  std::int64_t prev_ms = 0;
  for (const SeqEntry& e : entries) prev_ms += e.delay_ms;
  Session& s = *c->session;
  s.write_sequence(entries);
  const RegisterInfo& len = require_register("seq_len");
  const std::int16_t stored = s.read(len);
  if (stored != static_cast<std::int16_t>(entries.size())) {
    fail("{}: the board holds {} sequence entries after loading {}", link.port, stored, entries.size());
  }
  if (!options.then.empty()) {
    const RegisterInfo& state = require_register("seq_state");
    s.write(state, static_cast<std::int16_t>(parse_value(state, options.then, "--then")));
  }
  out << fmt::format("sequence: {} entries over {} s loaded{}\n", entries.size(),
                     config::format_number(static_cast<double>(prev_ms) * 1e-3),
                     options.then.empty() ? "" : fmt::format(", {}ing", options.then));
}

void run_serve(const LinkOptions& link, const ServeOptions& options) {
  auto c = connect(link, Hold::Serve);
  if (!c->owner) fail("{}: another {} holds the port and serves it already", link.port, link.tool);
  const InterruptGuard guard;
  const auto start = std::chrono::steady_clock::now();
  while (!InterruptGuard::interrupted()) {
    if (!c->owner->serving()) fail("{}: the port vanished", link.port);
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (options.seconds > 0.0 && elapsed >= options.seconds) break;
    ::usleep(50000);
  }
}

void run_monitor(const LinkOptions& link, const MonitorOptions& options, std::ostream& out) {
  if (::isatty(STDOUT_FILENO) != 1) fail("monitor: stdout is not a terminal (use 'stream' to capture data)");
  auto c = connect(link, Hold::Serve);
  Session& s = *c->session;
  const InterruptGuard guard;
  const RegisterInfo& rpm = require_register("rpm");
  const RegisterInfo& rpm_cmd = require_register("rpm_cmd");
  const RegisterInfo& duty = require_register("duty");
  const RegisterInfo& mode = require_register("mode");
  const RegisterInfo& flags = require_register("flags");
  const RegisterInfo& clutch = require_register("clutch");
  const RegisterInfo& load = require_register("load");
  const auto start = std::chrono::steady_clock::now();
  auto next = start;
  for (;;) {
    const std::string line =
        fmt::format("rpm {:>6}  cmd {:>4}  duty {:>6} %  mode {:<4} clutch {} load {}  {}",
                    format_value(rpm, s.read(rpm), 0), format_value(rpm_cmd, s.read(rpm_cmd), 0),
                    format_value(duty, s.read(duty), 0), format_value(mode, s.read(mode), 0),
                    format_value(clutch, s.read(clutch), 0), format_value(load, s.read(load), 0),
                    format_value(flags, s.read(flags), 0));
    out << "\r\033[K" << line << std::flush;
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(options.period_s));
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (InterruptGuard::interrupted() || (options.seconds > 0.0 && elapsed >= options.seconds)) break;
    while (!InterruptGuard::interrupted() && std::chrono::steady_clock::now() < next) {
      s.receive(std::chrono::duration<double>(next - std::chrono::steady_clock::now()).count());
    }
    if (InterruptGuard::interrupted()) break;
  }
  out << '\n' << std::flush;
}

}  // namespace mcg::link
