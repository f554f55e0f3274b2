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

struct Connection {
  std::unique_ptr<Port> port;
  std::unique_ptr<Session> session;
  Version version;

  /// F, the fractional bits of the coefficient registers (read once, cached).
  int frac_bits();
  void forget_frac_bits() { m_frac_bits.reset(); }
  /// "host firmware 0.2.0, protocol 2".
  std::string board_text() const;

 private:
  std::optional<int> m_frac_bits;
};

/// Opens link.port and checks the board's protocol version (Session::hello).
std::unique_ptr<Connection> connect(const LinkOptions& link);

/// The board registers, in engineering units, that realise the [controller] section of `ini`
/// (docs/formats.md), or none when there is no such section. The difference equation
///   sum_k a_k y[n-k] = sum_k b_k e[n-k],  e = input_scale (rpm_cmd - rpm),  duty = y / duty_full_scale
/// maps onto the board's laws when a = (1) (P: kp = b_0) or a = (1, -1) (incremental PI with
/// b_0, b_1, or PID with b_0, b_1, b_2), each coefficient scaled to the board's units
/// (1/1000 duty per pulse/ms, e in pulses per 1 ms at 2048 pulses/rev):
///   g_k = b_k / a_0 * input_scale * (60000 / 2048) * (1000 / duty_full_scale),
/// and coef_frac F chosen as the largest F <= 12 for which every g_k 2^F fits in 16 bits.
/// With a [fixed_point] section (mcg-design's integer form) its coefficients are used,
/// b_k = b<k>_q / 2^q_frac_bits, a_k = a<k>_q / 2^q_frac_bits, a_0 = 1: the quantised
/// controller the design analysed, re-quantised to the board's units (the board counts duty
/// in 1/1000 and errors at 2048 pulses/rev, so the design's integers do not carry over).
/// `output = duty` means duty_full_scale = 1.
/// Throws mcg::Error naming the file and key for a form the board cannot run (dt_s other
/// than 1 ms, other denominators, too many coefficients, coefficients too large).
std::vector<std::pair<const RegisterInfo*, double>> controller_registers(const config::Ini& ini);

}  // namespace mcg::link
