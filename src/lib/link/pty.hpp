// Pseudo-terminals that stand in for a serial port: the emulated board and the test relay.
#pragma once

#include <string>

namespace mcg::link {

/// The master side of a raw pseudo-terminal, with a symbolic link to its slave at a path of
/// the user's choice (e.g. ./ttyMCG), which programs open like a serial port.
///
/// The object keeps one descriptor of the slave open itself, so the master never sees a
/// hang-up while clients come and go; bytes written while no client listens wait in the
/// slave's input queue (clients flush it when they open the port). Destroying it removes the
/// link and closes the line, which every client sees as the port vanishing.
class PtyLink {
 public:
  /// Creates the pseudo-terminal in raw mode (no echo, no line editing), master
  /// non-blocking, and links `link_path` to its slave. An existing link to a pseudo-terminal
  /// (left by a crashed run) is replaced; any other file there is an error.
  explicit PtyLink(const std::string& link_path);
  ~PtyLink();
  PtyLink(const PtyLink&) = delete;
  PtyLink& operator=(const PtyLink&) = delete;

  /// The master descriptor (non-blocking): what the board reads and writes.
  int fd() const { return m_master; }
  const std::string& slave_path() const { return m_slave_path; }
  const std::string& link_path() const { return m_link; }

  /// Closes the line now (clients see the port vanish) and removes the link.
  void close();

 private:
  std::string m_link;
  std::string m_slave_path;
  int m_master = -1;
  int m_slave = -1;
};

}  // namespace mcg::link
