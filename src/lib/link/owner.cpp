// The port owner: a thread that holds the board's line and serves clients over a Unix socket.
#include "link/owner.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "common/demand.hpp"  // MCG_DEMAND
#include "common/error.hpp"   // mcg::fail
#include "common/poll_timeout.hpp"
#include "link/capture_meta.hpp"  // config_register_names
#include "link/frame.hpp"         // Decoder, encode
#include "link/registers.hpp"     // require_register
#include "mcg_protocol.h"         // MCG_CMD_*, MCG_MSG_*

namespace mcg::link {

namespace {

using Clock = std::chrono::steady_clock;

double now_s() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

/// A request goes to the board after the previous one was answered, or after this long.
constexpr double k_hold_s = 0.1;
/// While the stream is on it takes 56 of every 61 bytes the line carries at 9600 baud (a
/// 56-byte block per 64 ms): one answer of k_register_answer_bytes (a register) per this long
/// fits in the rest without making the board drop a block; a longer answer (MCG_CMD_READ_MANY)
/// holds the next request back in proportion to its length.
constexpr double k_stream_pace_s = 0.12;
constexpr std::size_t k_register_answer_bytes = MCG_FRAME_OVERHEAD + 1 + sizeof(McgRegisterAnswer);

/// The length on the wire of the answer to `request`.
std::size_t answer_bytes(const Frame& request) {
  if (request.cmd == MCG_CMD_READ_MANY && request.payload.size() == sizeof(McgReadManyRequest)) {
    return MCG_FRAME_OVERHEAD + 1 + sizeof(McgReadManyRequest) + 2u * request.payload[1];
  }
  if (request.cmd == MCG_CMD_READ_LIST) {
    return MCG_FRAME_OVERHEAD + 1 + sizeof(McgReadManyRequest) + 2u * request.payload.size();
  }
  return k_register_answer_bytes;
}
/// Registers in one MCG_CMD_READ_LIST while the stream is on: a 48-byte answer, which the
/// board's 128-byte transmit ring takes beside a 56-byte stream block with room to spare.
constexpr std::size_t k_list_streaming = 20;
static_assert(k_list_streaming <= MCG_READ_MANY_MAX);
/// An unanswered request is forgotten (its answer goes nowhere) after this long.
constexpr double k_forget_s = 10.0;
/// A client that does not read what it is sent is dropped beyond this backlog.
constexpr std::size_t k_max_backlog = 1u << 20;
constexpr double k_port_write_timeout_s = 2.0;
/// Stream blocks come every 64 ms: none for this long means the board's stream is off.
constexpr double k_stream_silent_s = 0.5;
/// While the stream is on, a read of a configuration register (one only a write changes) is answered
/// from the value the board gave for it at most this long ago: the line has room for one
/// answer per k_stream_pace_s, so twelve reads from the board would hold a capture's first
/// row back 1.5 s. Any other request (a write, a sequence, a log) forgets every such value.
constexpr double k_held_s = 5.0;
/// The owner reads a configuration register again in the line's spare room (no request
/// queued) once its value is this old, so the values stay within k_held_s.
constexpr double k_refresh_s = 2.0;
/// Registers the owner rereads in one MCG_CMD_READ_LIST: a 15-byte answer, which holds the next
/// request back 0.2 s while the stream runs; the held values take under 2 s to go round.
constexpr std::size_t k_refresh_list = 4;
/// ... once no client has asked the board anything for this long (a client reading register
/// after register has the line to itself).
constexpr double k_client_quiet_s = 0.3;

sockaddr_un socket_address(const std::string& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof addr.sun_path) fail("{}: control socket path too long", path);
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  return addr;
}

/// A byte line over a connected stream socket (the client's end of the owner's service).
class SocketPort final : public Port {
 public:
  SocketPort(std::string name, int fd) : m_name(std::move(name)), m_fd(fd) {}
  ~SocketPort() override { ::close(m_fd); }
  const std::string& name() const override { return m_name; }

  std::size_t read_some(std::span<std::uint8_t> buf, double timeout_s) override {
    pollfd p{m_fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, poll_timeout_ms(timeout_s));
    if (ready < 0) {
      if (errno == EINTR) return 0;
      fail("{}: waiting for input: {}", m_name, std::strerror(errno));
    }
    if (ready == 0) return 0;
    const ssize_t n = ::recv(m_fd, buf.data(), buf.size(), MSG_DONTWAIT);
    if (n > 0) return static_cast<std::size_t>(n);
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) return 0;
    vanished();
  }

  void write_all(std::span<const std::uint8_t> bytes, double timeout_s) override {
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
    while (!bytes.empty()) {
      const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
      if (left <= 0.0) fail("{}: write timed out after {} s (the port's owner does not read)", m_name, timeout_s);
      pollfd p{m_fd, POLLOUT, 0};
      const int ready = ::poll(&p, 1, poll_timeout_ms(left));
      if (ready < 0 && errno != EINTR) fail("{}: waiting to write: {}", m_name, std::strerror(errno));
      if (ready <= 0) continue;
      const ssize_t n = ::send(m_fd, bytes.data(), bytes.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
      if (n < 0) {
        if (errno == EAGAIN || errno == EINTR) continue;
        vanished();
      }
      bytes = bytes.subspan(static_cast<std::size_t>(n));
    }
  }

  void discard_input() override {
    std::uint8_t buf[512];
    while (::recv(m_fd, buf, sizeof buf, MSG_DONTWAIT) > 0) {
    }
  }

 private:
  [[noreturn]] void vanished() const { throw PortVanished(fmt::format("{}: the port vanished", m_name)); }

  std::string m_name;
  int m_fd;
};

/// A client's MCG_CMD_READ_MANY that the owner answers itself: the configuration registers from
/// the values it holds, the others from the board in MCG_CMD_READ_LIST parts, then one answer in
/// READ_MANY's form. While the stream runs the line has room for a few short answers a second,
/// so a read-back of every register asks the board only for what it changes itself.
struct Gathered {
  int client = -1;
  Frame request;                                    ///< the client's READ_MANY
  std::vector<std::optional<std::int16_t>> values;  ///< registers first..first + count - 1
  std::size_t parts_left = 0;
  bool done = false;  ///< answered or refused
};

/// A request not sent yet (client -1: the owner's own).
struct Pending {
  int client = -1;
  Frame frame;
  std::shared_ptr<Gathered> gathered;  ///< the READ_MANY this READ_LIST is a part of
};

/// The answer a request expects: its command with the reply bit and, for register reads and
/// writes, the register echoed in the answer.
struct Expect {
  int client = -1;
  std::uint8_t answer = 0;
  int reg = -1;
  double sent_s = 0.0;
  std::uint64_t generation = 0;  ///< of the held values when it was sent
  std::vector<std::uint8_t> listed;    ///< the registers of a READ_LIST, in order
  std::shared_ptr<Gathered> gathered;  ///< see Pending
};

Expect expectation(const Pending& p) {
  const Frame& request = p.frame;
  Expect e;
  e.client = p.client;
  e.answer = static_cast<std::uint8_t>(request.cmd | MCG_REPLY_BIT);
  const bool echoes = request.cmd == MCG_CMD_READ || request.cmd == MCG_CMD_WRITE ||
                      request.cmd == MCG_CMD_READ_MANY || request.cmd == MCG_CMD_READ_LIST;
  if (echoes && !request.payload.empty()) {
    e.reg = request.payload[0];
  }
  if (request.cmd == MCG_CMD_READ_LIST) e.listed = request.payload;
  e.gathered = p.gathered;
  return e;
}

/// A request that changes nothing on the board (a read, the version).
bool is_read(std::uint8_t cmd) {
  return cmd == MCG_CMD_READ || cmd == MCG_CMD_READ_MANY || cmd == MCG_CMD_READ_LIST ||
         cmd == MCG_CMD_VERSION;
}

bool answers(const Expect& e, const Frame& f) {
  if (f.cmd != e.answer) return false;
  // A refusal carries the status only; an accepted read or write echoes the register.
  if (e.reg >= 0 && f.payload.size() >= 2 && f.payload[0] == MCG_ST_OK) return f.payload[1] == e.reg;
  return true;
}

}  // namespace

std::string control_socket_path(const std::string& port) {
  std::string key = port;
  if (char* real = ::realpath(port.c_str(), nullptr)) {
    key = real;
    std::free(real);
  }
  std::string name;
  for (char c : key) name += (c == '/' || c == ' ') ? '_' : c;
  while (!name.empty() && name.front() == '_') name.erase(0, 1);
  const char* dir = std::getenv("XDG_RUNTIME_DIR");
  std::string base = (dir != nullptr && *dir != '\0') ? std::string(dir) : std::string("/tmp");
  std::string path = fmt::format("{}/mcg-serial.{}.sock", base, name);
  if (path.size() >= sizeof(sockaddr_un{}.sun_path)) {
    path = fmt::format("{}/mcg-serial.{:016x}.sock", base, std::hash<std::string>{}(key));
  }
  return path;
}

std::unique_ptr<Port> connect_owner(const std::string& port) {
  const std::string path = control_socket_path(port);
  const sockaddr_un addr = socket_address(path);
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) fail("{}: cannot make a socket: {}", path, std::strerror(errno));
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return nullptr;
  }
  return std::make_unique<SocketPort>(port, fd);
}

std::unique_ptr<Port> open_shared_port(const std::string& port, int baud) {
  if (auto p = connect_owner(port)) return p;
  const auto deadline = Clock::now() + std::chrono::seconds(1);
  for (;;) {
    try {
      return open_port(port, baud);
    } catch (const PortVanished&) {
      throw;
    } catch (const Error& e) {
      // Busy: an owner may be between opening the port and listening. Anything else is final.
      if (std::string_view(e.what()).find("port busy") == std::string_view::npos || Clock::now() > deadline) throw;
    }
    ::usleep(20000);
    if (auto p = connect_owner(port)) return p;
  }
}

struct PortOwner::Impl {
  struct Client {
    int fd = -1;
    int id = 0;
    Decoder decoder{1.0};
    std::vector<std::uint8_t> backlog;   ///< bytes for the client its socket did not take yet
    bool stream = false;                 ///< turned the stream on
    bool closed = false;
  };

  std::unique_ptr<Port> port;
  std::string path;
  int listen_fd = -1;
  int wake[2] = {-1, -1};   ///< the owner's destructor wakes the thread through it
  std::thread thread;
  std::atomic<bool> serving{true};
  std::vector<Client> clients;
  int next_id = 1;
  Decoder board{0.1};
  std::deque<Pending> queue;                 ///< requests not sent yet
  std::vector<Expect> expected;              ///< sent, not answered
  double last_sent_s = -1e9;
  double pace_s = k_stream_pace_s;  ///< while streaming, the gap the last request's answer needs
  double last_block_s = -1e9;                ///< when the last stream block arrived
  double last_client_s = -1e9;               ///< when a client last asked the board something
  bool waiting = false;                      ///< the last request sent has no answer yet
  int log_client = -1;                       ///< who asked for the log dump
  std::uint8_t stream_reg = 0;
  std::uint8_t seq_state_reg = 0;
  std::uint8_t exc_run_reg = 0;
  std::uint8_t commit_reg = 0;
  std::vector<std::uint8_t> staged_regs;  ///< the controller's set, which a commit makes active
  bool finishing = false;  ///< the owner's process is done: serve the rest, then end
  int stager = -1;         ///< the client whose staged writes the shadow set holds
  double stager_last_s = 0.0;        ///< when it last wrote the controller's set
  std::vector<int> dropped_stagers;  ///< clients whose staged set the owner discarded

  /// A configuration register's value as the board last answered a read of it.
  struct Held {
    std::uint8_t reg = 0;
    std::optional<std::int16_t> raw;
    double at_s = 0.0;
  };
  std::vector<Held> held;
  std::uint64_t generation = 0;   ///< bumped whenever the held values are forgotten
  bool sequence_may_play = true;  ///< until a read of seq_state says it stopped
  bool excitation_may_run = true;  ///< until a read of exc_run says it stopped
  std::optional<Frame> version;   ///< the board's answer to MCG_CMD_VERSION (it never changes)

  Held* held_for(int reg) {
    for (auto& h : held) {
      if (h.reg == reg) return &h;
    }
    return nullptr;
  }

  void forget_held() {
    ++generation;
    for (auto& h : held) h.raw.reset();
  }

  /// Forgets the held values a request `cmd` (naming register `reg`) may change: a write, its
  /// register; a commit, the controller's set; a sequence or an excitation started, every value
  /// (the board then writes registers itself). The log and sequence storage change none.
  void forget_for(std::uint8_t cmd, int reg) {
    if (cmd == MCG_CMD_LOG_START || cmd == MCG_CMD_LOG_DUMP || cmd == MCG_CMD_SEQ_WRITE ||
        cmd == MCG_CMD_SEQ_CLEAR) {
      return;
    }
    if (cmd != MCG_CMD_WRITE || reg < 0 || reg == seq_state_reg || reg == exc_run_reg) {
      forget_held();
      return;
    }
    ++generation;  // an answer to a read sent before the write may hold its old value
    for (auto& h : held) {
      const bool staged = std::find(staged_regs.begin(), staged_regs.end(), h.reg) != staged_regs.end();
      if (h.reg == reg || (reg == commit_reg && staged)) h.raw.reset();
    }
  }

  /// The board may be writing registers itself (a sequence playing, an excitation running).
  bool board_plays() const { return sequence_may_play || excitation_may_run; }

  /// Register `reg` as the owner may answer it: a configuration register while the stream is
  /// on and the board does not play, from the board's answer of less than k_held_s ago.
  std::optional<std::int16_t> held_value(int reg) {
    if (!anyone_streams(-1) || board_plays()) return {};
    const Held* h = held_for(reg);
    if (h == nullptr || !h->raw || now_s() - h->at_s > k_held_s) return {};
    return h->raw;
  }

  /// The answer to `f` from what the owner holds, if it may give one: the version always, a
  /// configuration register as held_value() allows.
  std::optional<Frame> answer_here(const Frame& f) {
    if (f.cmd == MCG_CMD_VERSION && f.payload.empty()) return version;
    if (f.cmd != MCG_CMD_READ || f.payload.size() != 1) return {};
    const auto raw = held_value(f.payload[0]);
    if (!raw) return {};
    Frame reply;
    reply.cmd = static_cast<std::uint8_t>(MCG_CMD_READ | MCG_REPLY_BIT);
    reply.payload = {MCG_ST_OK, f.payload[0]};
    put_i16(reply.payload, *raw);
    return reply;
  }

  /// Takes client `c`'s MCG_CMD_READ_MANY `f` over as a Gathered (false: `f` is malformed or
  /// names registers that do not exist, and goes to the board, which refuses it).
  bool gather(Client& c, const Frame& f) {
    if (f.payload.size() != sizeof(McgReadManyRequest)) return false;
    const unsigned first = f.payload[0];
    const unsigned count = f.payload[1];
    if (first == 0 || count == 0 || count > MCG_READ_MANY_MAX || first + count > MCG_REG_COUNT) return false;
    const bool again = std::any_of(queue.begin(), queue.end(), [&](const Pending& p) {
      return p.gathered && p.gathered->client == c.id && p.gathered->request.payload == f.payload;
    });
    if (again) return true;  // a resend while the first still waits for its turn asks once
    auto g = std::make_shared<Gathered>();
    g->client = c.id;
    g->request = f;
    std::vector<std::uint8_t> needed;
    for (unsigned k = 0; k < count; ++k) {
      g->values.push_back(held_value(static_cast<int>(first + k)));
      if (!g->values.back()) needed.push_back(static_cast<std::uint8_t>(first + k));
    }
    if (needed.empty()) {
      answer_gathered(*g);
      return true;
    }
    last_client_s = now_s();
    const std::size_t part = anyone_streams(-1) ? k_list_streaming : MCG_READ_MANY_MAX;
    for (std::size_t at = 0; at < needed.size(); at += part) {
      Pending p;
      p.client = c.id;
      p.frame.cmd = MCG_CMD_READ_LIST;
      p.frame.payload.assign(
          needed.begin() + static_cast<std::ptrdiff_t>(at),
          needed.begin() + static_cast<std::ptrdiff_t>(std::min(needed.size(), at + part)));
      p.gathered = g;
      ++g->parts_left;
      queue.push_back(std::move(p));
    }
    return true;
  }

  /// The board answered part `e` of a Gathered with `f`.
  void gathered_part(const Expect& e, const Frame& f) {
    Gathered& g = *e.gathered;
    if (g.done) return;
    --g.parts_left;
    const std::size_t head = 1 + sizeof(McgReadManyRequest);
    if (f.payload.empty() || f.payload[0] != MCG_ST_OK || f.payload.size() != head + 2 * e.listed.size()) {
      Frame refusal;
      refusal.cmd = static_cast<std::uint8_t>(MCG_CMD_READ_MANY | MCG_REPLY_BIT);
      refusal.payload = {f.payload.empty() || f.payload[0] == MCG_ST_OK ? std::uint8_t{MCG_ST_BAD_LENGTH}
                                                                        : f.payload[0]};
      g.done = true;
      if (Client* c = find(g.client)) send_to(*c, refusal);
      return;
    }
    const unsigned first = g.request.payload[0];
    for (std::size_t k = 0; k < e.listed.size(); ++k)
      g.values.at(e.listed[k] - first) = get_i16(f.payload, head + 2 * k);
    if (g.parts_left == 0) answer_gathered(g);
  }

  void answer_gathered(Gathered& g) {
    Frame reply;
    reply.cmd = static_cast<std::uint8_t>(MCG_CMD_READ_MANY | MCG_REPLY_BIT);
    reply.payload = {MCG_ST_OK, g.request.payload[0], g.request.payload[1]};
    for (const auto& v : g.values) {
      MCG_DEMAND(v.has_value());
      put_i16(reply.payload, *v);
    }
    g.done = true;
    if (Client* c = find(g.client)) send_to(*c, reply);
  }

  /// What an answer from the board tells the owner about the values it holds.
  void learn(const Expect& e, const Frame& f) {
    if (f.payload.empty() || f.payload[0] != MCG_ST_OK) return;
    const auto cmd = static_cast<std::uint8_t>(f.cmd & ~MCG_REPLY_BIT);
    if (cmd == MCG_CMD_VERSION) {
      version = f;
      return;
    }
    if (!is_read(cmd)) {
      forget_for(cmd, e.reg);
      return;
    }
    if (e.generation != generation) return;
    if (cmd == MCG_CMD_READ) {
      if (f.payload.size() >= 1 + sizeof(McgRegisterAnswer)) hold(f.payload[1], get_i16(f.payload, 2));
      return;
    }
    const std::size_t head = 1 + sizeof(McgReadManyRequest);
    if (cmd == MCG_CMD_READ_LIST) {
      if (f.payload.size() != head + 2 * e.listed.size()) return;
      for (std::size_t k = 0; k < e.listed.size(); ++k) hold(e.listed[k], get_i16(f.payload, head + 2 * k));
      return;
    }
    if (f.payload.size() < head || f.payload.size() != head + 2u * f.payload[2]) return;
    for (std::size_t k = 0; k < f.payload[2]; ++k) {
      hold(static_cast<int>(f.payload[1] + k), get_i16(f.payload, head + 2 * k));
    }
  }

  /// The board just answered `raw` for register `reg`.
  void hold(int reg, std::int16_t raw) {
    if (reg == seq_state_reg) sequence_may_play = raw != MCG_SEQ_STOP;
    if (reg == exc_run_reg) excitation_may_run = raw != 0;
    if (Held* h = held_for(reg)) {
      h->raw = raw;
      h->at_s = now_s();
    }
  }

  /// In the line's spare room while streaming: the owner's own read of the configuration
  /// registers due (seq_state and exc_run first while the board may play).
  void refresh_held() {
    const double now = now_s();
    if (waiting || !queue.empty() || !anyone_streams(-1) || now - last_client_s < k_client_quiet_s) return;
    Frame f;
    f.cmd = MCG_CMD_READ;
    if (board_plays()) {
      if (sequence_may_play) f.payload.push_back(seq_state_reg);
      if (excitation_may_run) f.payload.push_back(exc_run_reg);
      if (f.payload.size() > 1) f.cmd = MCG_CMD_READ_LIST;
    } else {
      for (const Held& h : held) {
        if ((!h.raw || now - h.at_s > k_refresh_s) && f.payload.size() < k_refresh_list)
          f.payload.push_back(h.reg);
      }
      if (f.payload.empty()) return;
      if (f.payload.size() > 1) f.cmd = MCG_CMD_READ_LIST;
    }
    queue.push_back({-1, std::move(f), nullptr});
  }

  Client* find(int id) {
    for (auto& c : clients) {
      if (c.id == id && !c.closed) return &c;
    }
    return nullptr;
  }

  void send_to(Client& c, const Frame& f) {
    if (c.closed) return;
    const std::vector<std::uint8_t> bytes = encode(f.cmd, f.payload);
    c.backlog.insert(c.backlog.end(), bytes.begin(), bytes.end());
    flush_client(c);
  }

  void flush_client(Client& c) {
    while (!c.backlog.empty() && !c.closed) {
      const ssize_t n = ::send(c.fd, c.backlog.data(), c.backlog.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
      if (n < 0) {
        if (errno == EINTR) continue;
        if (errno != EAGAIN) c.closed = true;
        break;
      }
      c.backlog.erase(c.backlog.begin(), c.backlog.begin() + n);
    }
    if (c.backlog.size() > k_max_backlog) c.closed = true;
  }

  bool anyone_streams(int except) const {
    return std::any_of(clients.begin(), clients.end(),
                       [&](const Client& c) { return !c.closed && c.id != except && c.stream; });
  }

  /// `f` writes the board's shadow set: a register of the controller's set, or commit.
  bool stages(const Frame& f) const {
    if (f.cmd != MCG_CMD_WRITE || f.payload.size() < 3) return false;
    return f.payload[0] == commit_reg ||
           std::find(staged_regs.begin(), staged_regs.end(), f.payload[0]) != staged_regs.end();
  }

  /// Whether client `c` may write the shadow set with `f`: no other client's set is staged,
  /// and `c`'s own was not discarded since it began (a discard, commit 0, begins afresh). A
  /// commit 1 ends the client's hold; the owner refuses the others BUSY meanwhile, which the
  /// board never answers to a staged write or a commit.
  bool may_stage(Client& c, const Frame& f) {
    const bool commit = f.payload[0] == commit_reg;
    const std::int16_t value = get_i16(f.payload, 1);
    const auto dropped = std::find(dropped_stagers.begin(), dropped_stagers.end(), c.id);
    if (dropped != dropped_stagers.end()) {
      if (!commit || value != 0) return false;
      dropped_stagers.erase(dropped);
    }
    if (stager >= 0 && stager != c.id) return false;
    stager = commit && value != 0 ? -1 : c.id;
    stager_last_s = now_s();
    return true;
  }

  /// Discards the shadow set of a stager that left or went silent (the board's commit 0).
  void drop_stager(bool silent) {
    if (silent) dropped_stagers.push_back(stager);
    stager = -1;
    queue_own_write(commit_reg, 0);
  }

  /// A write of the owner's own to the board, after what is queued.
  void queue_own_write(std::uint8_t reg, std::int16_t value) {
    Frame f;
    f.cmd = MCG_CMD_WRITE;
    f.payload = {reg};
    put_i16(f.payload, value);
    queue.push_back({-1, std::move(f), nullptr});
  }

  /// A whole frame from client `c`: queued for the board, or answered here when it would
  /// turn off a stream another client still reads.
  void from_client(Client& c, Frame f) {
    if (f.cmd == MCG_CMD_WRITE && f.payload.size() >= 3 && f.payload[0] == stream_reg) {
      const bool on = get_i16(f.payload, 1) != 0;
      c.stream = on;
      // The stream is on while anyone reads it: writing what it already is would restart the
      // board's block (a gap for the others), writing it off would end theirs. Blocks that
      // stopped coming (a board that reset) need the write.
      if (anyone_streams(c.id) && (!on || now_s() - last_block_s < k_stream_silent_s)) {
        Frame reply;
        reply.cmd = static_cast<std::uint8_t>(MCG_CMD_WRITE | MCG_REPLY_BIT);
        reply.payload = {MCG_ST_OK, stream_reg};
        put_i16(reply.payload, 1);
        send_to(c, reply);
        return;
      }
    }
    if (stages(f) && !may_stage(c, f)) {
      Frame refusal;
      refusal.cmd = static_cast<std::uint8_t>(MCG_CMD_WRITE | MCG_REPLY_BIT);
      refusal.payload = {MCG_ST_BUSY};
      send_to(c, refusal);
      return;
    }
    if (auto reply = answer_here(f)) {
      send_to(c, *reply);
      return;
    }
    if (f.cmd == MCG_CMD_READ_MANY && gather(c, f)) return;
    last_client_s = now_s();
    if (f.cmd == MCG_CMD_LOG_DUMP) log_client = c.id;
    // A client that resends while its request still waits for its turn asks once.
    const bool again = std::any_of(queue.begin(), queue.end(), [&](const Pending& p) {
      return p.client == c.id && p.frame.cmd == f.cmd && p.frame.payload == f.payload;
    });
    if (!again) queue.push_back({c.id, std::move(f), nullptr});
  }

  void from_board(const Frame& f) {
    if (f.cmd == MCG_MSG_STREAM) {
      last_block_s = now_s();
      for (auto& c : clients) {
        if (c.stream) send_to(c, f);
      }
      return;
    }
    if (f.cmd == MCG_MSG_LOG_DATA) {
      if (Client* c = find(log_client)) send_to(*c, f);
      return;
    }
    if (f.cmd == MCG_MSG_ERROR) {
      // A damaged frame: whoever waits for an answer resends at once.
      std::vector<int> told;
      for (const auto& e : expected) {
        if (std::find(told.begin(), told.end(), e.client) != told.end()) continue;
        told.push_back(e.client);
        if (Client* c = find(e.client)) send_to(*c, f);
      }
      waiting = false;
      return;
    }
    const auto it = std::find_if(expected.begin(), expected.end(), [&](const Expect& e) { return answers(e, f); });
    if (it == expected.end()) return;
    const Expect e = std::move(*it);
    expected.erase(it);
    learn(e, f);
    waiting = false;
    if (e.gathered) {
      gathered_part(e, f);
    } else if (Client* c = find(e.client)) {
      send_to(*c, f);
    }
  }

  void send_next() {
    const double now = now_s();
    if (stager >= 0 && now - stager_last_s > k_stage_idle_s) drop_stager(true);
    std::erase_if(expected, [&](const Expect& e) { return now - e.sent_s > k_forget_s; });
    if (waiting && now - last_sent_s >= k_hold_s) waiting = false;
    refresh_held();
    if (queue.empty() || waiting) return;
    if (anyone_streams(-1) && now - last_sent_s < pace_s) return;
    Pending p = std::move(queue.front());
    queue.pop_front();
    const Frame& f = p.frame;
    if (!is_read(f.cmd)) {
      const bool write = f.cmd == MCG_CMD_WRITE && f.payload.size() >= 3;
      forget_for(f.cmd, write ? f.payload[0] : -1);
      if (write && f.payload[0] == seq_state_reg && get_i16(f.payload, 1) != MCG_SEQ_STOP)
        sequence_may_play = true;
      if (write && f.payload[0] == exc_run_reg && get_i16(f.payload, 1) != 0) excitation_may_run = true;
    }
    port->write_all(encode(f.cmd, f.payload), k_port_write_timeout_s);
    Expect e = expectation(p);
    e.sent_s = now;
    e.generation = generation;
    expected.push_back(e);
    last_sent_s = now;
    pace_s = k_stream_pace_s * static_cast<double>(answer_bytes(f)) / static_cast<double>(k_register_answer_bytes);
    waiting = true;
  }

  void drop_closed() {
    bool stopped_streaming = false;
    for (auto& c : clients) {
      if (!c.closed) continue;
      stopped_streaming = stopped_streaming || c.stream;
      std::erase_if(queue, [&](const Pending& p) { return p.client == c.id; });
      std::erase(dropped_stagers, c.id);
      if (c.id == stager) drop_stager(false);
      ::close(c.fd);
      c.fd = -1;
    }
    std::erase_if(clients, [](const Client& c) { return c.fd < 0; });
    if (stopped_streaming && !anyone_streams(-1)) {
      // The last reader of the stream went away without turning it off.
      queue_own_write(stream_reg, 0);
    }
  }

  void accept_clients() {
    for (;;) {
      const int fd = ::accept4(listen_fd, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
      if (fd < 0) return;
      add_client(fd);
    }
  }

  void add_client(int fd) {
    Client c;
    c.fd = fd;
    c.id = next_id++;
    clients.push_back(std::move(c));
  }

  void read_client(Client& c) {
    std::uint8_t buf[4096];
    const ssize_t n = ::recv(c.fd, buf, sizeof buf, MSG_DONTWAIT);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) {
      c.closed = true;
      return;
    }
    if (n < 0) return;
    std::vector<Frame> frames;
    c.decoder.feed(std::span<const std::uint8_t>(buf, static_cast<std::size_t>(n)), now_s(), frames);
    for (auto& f : frames) from_client(c, std::move(f));
  }

  void serve() {
    sigset_t block;
    sigemptyset(&block);
    sigaddset(&block, SIGINT);
    sigaddset(&block, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &block, nullptr);
    try {
      loop();
    } catch (const Error&) {
      // The port vanished or stays blocked: every client sees its line end.
    }
    for (auto& c : clients) {
      ::close(c.fd);
      c.fd = -1;
    }
    clients.clear();
    close_listener();
    serving = false;
  }

  void loop() {
    std::uint8_t buf[512];
    for (;;) {
      std::vector<pollfd> fds;
      fds.push_back({finishing ? -1 : wake[0], POLLIN, 0});
      fds.push_back({listen_fd, POLLIN, 0});
      fds.push_back({port->poll_fd(), POLLIN, 0});
      for (const auto& c : clients) {
        fds.push_back({c.fd, static_cast<short>(POLLIN | (c.backlog.empty() ? 0 : POLLOUT)), 0});
      }
      double timeout_s = 0.05;
      if (!queue.empty()) {
        const double gap_s = std::max(waiting ? k_hold_s : 0.0, anyone_streams(-1) ? pace_s : 0.0);
        timeout_s = std::clamp(gap_s - (now_s() - last_sent_s), 0.0, timeout_s);
      }
      if (fds[2].fd < 0) timeout_s = std::min(timeout_s, 0.002);
      const int ready = ::poll(fds.data(), fds.size(), poll_timeout_ms(timeout_s));
      if (ready < 0 && errno != EINTR) fail("control socket: poll: {}", std::strerror(errno));
      if (ready > 0 && fds[0].revents != 0 && !finishing) {
        finishing = true;
      }
      if (finishing && clients.empty() && queue.empty() && !waiting) {
        accept_clients();  // one that connected just now is served too
        if (clients.empty()) return;
      }
      if (ready > 0 && (fds[1].revents & POLLIN) != 0) accept_clients();
      if (fds[2].fd < 0 || (ready > 0 && fds[2].revents != 0)) {
        const std::size_t n = port->read_some(buf, 0.0);
        std::vector<Frame> frames;
        if (n > 0) board.feed(std::span<const std::uint8_t>(buf, n), now_s(), frames);
        for (const auto& f : frames) from_board(f);
      } else {
        std::vector<Frame> frames;
        board.poll(now_s(), frames);
        for (const auto& f : frames) from_board(f);
      }
      for (std::size_t k = 3; k < fds.size(); ++k) {
        Client* c = find(clients[k - 3].id);
        if (c == nullptr || fds[k].revents == 0) continue;
        if ((fds[k].revents & POLLOUT) != 0) flush_client(*c);
        if ((fds[k].revents & (POLLIN | POLLHUP | POLLERR)) != 0) read_client(*c);
      }
      drop_closed();
      send_next();
    }
  }

  void close_listener() {
    if (listen_fd >= 0) {
      ::close(listen_fd);
      listen_fd = -1;
      ::unlink(path.c_str());
    }
  }
};

PortOwner::PortOwner(std::unique_ptr<Port> port) : m_impl(std::make_unique<Impl>()) {
  Impl& m = *m_impl;
  m.port = std::move(port);
  m.stream_reg = require_register("stream").id;
  m.seq_state_reg = require_register("seq_state").id;
  m.exc_run_reg = require_register("exc_run").id;
  m.commit_reg = require_register("commit").id;
  for (const RegisterInfo& reg : registers()) {
    if (reg.staged) m.staged_regs.push_back(reg.id);
  }
  // board_config's registers first (a capture's header needs them), then every other one that
  // only a write changes: not the duty a closed loop drives, a counter, or a sequence's state.
  for (const std::string_view name : config_register_names())
    m.held.push_back({require_register(name).id, std::nullopt, 0.0});
  for (const RegisterInfo& reg : registers()) {
    if (!reg.writable || reg.name == "duty" || reg.name == "tx_drops" || reg.name == "seq_state") continue;
    if (m.held_for(reg.id) == nullptr) m.held.push_back({reg.id, std::nullopt, 0.0});
  }
  m.path = control_socket_path(m.port->name());
  const sockaddr_un addr = socket_address(m.path);
  m.listen_fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (m.listen_fd < 0) fail("{}: cannot make a socket: {}", m.path, std::strerror(errno));
  // This process holds the port exclusively, so a socket already there is a dead owner's.
  ::unlink(m.path.c_str());
  if (::bind(m.listen_fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 ||
      ::listen(m.listen_fd, 16) != 0) {
    const int err = errno;
    ::close(m.listen_fd);
    fail("{}: cannot listen for the port's other clients: {}", m.path, std::strerror(err));
  }
  if (::pipe2(m.wake, O_CLOEXEC) != 0) {
    m.close_listener();
    fail("cannot make a pipe: {}", std::strerror(errno));
  }
  m.port->discard_input();
  m.thread = std::thread([&m] { m.serve(); });
}

PortOwner::~PortOwner() {
  Impl& m = *m_impl;
  // Closing the pipe's write end wakes the thread's poll (POLLHUP): it serves the clients
  // still connected until the last one leaves, then ends.
  ::close(m.wake[1]);
  m.thread.join();
  ::close(m.wake[0]);
}

bool PortOwner::serving() const { return m_impl->serving; }

std::unique_ptr<Port> PortOwner::local_client() {
  auto p = connect_owner(m_impl->port->name());
  if (!p) fail("{}: cannot reach this process's own control socket", m_impl->path);
  return p;
}

}  // namespace mcg::link
