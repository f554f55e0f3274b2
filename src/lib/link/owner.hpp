// One owner of the port: the mcg-serial that holds the board serves every other mcg-serial on
// the same port through a Unix control socket, one whole frame at a time.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "link/port.hpp"  // Port

namespace mcg::link {

/// A client staging the controller's set through a shared port and silent this long loses the
/// shadow set (PortOwner).
inline constexpr double k_stage_idle_s = 5.0;

/// The control socket of `port`: named after the device the path resolves to (so every
/// spelling of one port finds the same owner), in $XDG_RUNTIME_DIR, else /tmp.
std::string control_socket_path(const std::string& port);

/// A Port whose bytes go through the owner of `port`, named `port` in messages; nullptr when
/// no owner listens (no socket, or a stale one its dead owner left: the caller opens the port
/// itself, and the next owner replaces the socket).
std::unique_ptr<Port> connect_owner(const std::string& port);

/// Opens `port` for this process: through its owner when one listens, else the port itself
/// (retrying the owner for a moment when the port is busy, as an owner is between opening the
/// port and listening). Errors as open_port().
std::unique_ptr<Port> open_shared_port(const std::string& port, int baud);

/// Holds an open port and serves it: every client (connect_owner, and local_client() for the
/// owner's own conversation) sends whole frames; they go to the board one request at a time
/// (the next after the answer, or after 0.1 s without one), and never interleaved. Answers go
/// back to the client that asked (by command and register, oldest first); stream blocks to
/// the clients that turned the stream on (the stream stays on while one of them wants it);
/// log data to the client that asked for the dump; the board's frame-error reports to the
/// clients waiting for an answer. When the port vanishes every client sees its line vanish.
/// The version, and while the stream is on a register that only a write changes (not duty,
/// tx_drops, seq_state, the measurements) read from the board less than 5 s ago with no
/// request but reads since, are answered from what the owner holds; it rereads those
/// registers in the line's spare room, so a client's capture starts without a dozen round
/// trips between stream blocks. A keypad edit on the board shows within 5 s.
/// The board's shadow set is one client's at a time: from its first staged write (or commit 0)
/// to its commit 1 the others' staged writes and commits are refused BUSY; a client that leaves
/// or stays silent for k_stage_idle_s loses it, the owner discards its set (commit 0) and
/// refuses the rest of its set until it begins again with commit 0.
class PortOwner {
 public:
  /// Takes `port` and listens on control_socket_path(port->name()), replacing a stale socket.
  explicit PortOwner(std::unique_ptr<Port> port);
  /// Serves the clients still connected (a newcomer too) until the last one leaves, so that
  /// none of them sees the port vanish; a signal that kills the process ends them all.
  ~PortOwner();
  PortOwner(const PortOwner&) = delete;
  PortOwner& operator=(const PortOwner&) = delete;

  /// A Port for this process's own conversation with the board (a client like the others).
  std::unique_ptr<Port> local_client();
  /// False once the port vanished (or stayed blocked) and the service ended.
  bool serving() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace mcg::link
