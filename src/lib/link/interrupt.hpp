// Ctrl-C for long-running link commands: a flag the waits check, no abrupt exit.
#pragma once

#include <csignal>

namespace mcg::link {

/// While alive, SIGINT and SIGTERM set a flag instead of ending the process, and interrupt
/// the poll() a Port waits in (no SA_RESTART), so a capture can end cleanly and keep its data.
/// The previous handlers come back on destruction.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  /// True once SIGINT or SIGTERM arrived.
  static bool interrupted();

 private:
  struct sigaction m_old_int {};
  struct sigaction m_old_term {};
};

}  // namespace mcg::link
