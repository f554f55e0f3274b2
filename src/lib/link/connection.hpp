// An open port with a checked session: what every board subcommand starts from.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "link/port.hpp"       // Port
#include "link/registers.hpp"  // RegisterInfo
#include "link/serial.hpp"     // LinkOptions
#include "link/session.hpp"    // Session, Version

namespace mcg::config {
class Ini;
}

namespace mcg::link {

class PortOwner;

struct Connection {
  Connection();
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  /// When this process owns the port and serves the others (declared first: it ends last).
  std::unique_ptr<PortOwner> owner;
  std::unique_ptr<Port> port;
  std::unique_ptr<Session> session;
  Version version;

  /// F, the fractional bits of the coefficient registers (read once, cached).
  int frac_bits();
  void forget_frac_bits() { m_frac_bits.reset(); }
  /// F as the gains that follow are to be written: the coef_frac just staged.
  void set_frac_bits(int frac_bits) { m_frac_bits = frac_bits; }
  /// "host firmware 0.4.0, protocol 4".
  std::string board_text() const;

 private:
  std::optional<int> m_frac_bits;
};

/// How a command holds the port when no other mcg-serial owns it.
enum class Hold {
  Alone,   ///< a short command (get, set, load, dump, send): opens the port for itself
  Serve,   ///< a long one (stream, monitor, console, serve): owns the port and serves the others
};

/// Reaches the board on link.port (through its owner when another mcg-serial holds it, see
/// PortOwner) and checks its protocol version (Session::hello).
std::unique_ptr<Connection> connect(const LinkOptions& link, Hold hold = Hold::Alone);

/// The board registers, in engineering units, that realise the [controller] section of `ini`
/// (docs/formats.md), or none when there is none: boardunits::board_controller's registers
/// (its [fixed_point] bit for bit, or the [controller] quantised), coef_frac first and mode
/// last. Throws mcg::Error naming the file and key, and what the board can run, for a form it
/// cannot run.
std::vector<std::pair<const RegisterInfo*, double>> controller_registers(const config::Ini& ini);

}  // namespace mcg::link
