// Diagnostics: the one place a tool's messages get their prefix and kind.
#include "common/diagnostics.hpp"

#include <fmt/format.h>

#include <ostream>

namespace mcg {

void Diagnostics::warning(std::string_view message) {
  *m_out << fmt::format("{}: warning: {}\n", m_prefix, message);
}

void Diagnostics::note(std::string_view message) {
  *m_out << fmt::format("{}: note: {}\n", m_prefix, message);
}

void Diagnostics::error(std::string_view message, int status) {
  *m_out << fmt::format("{}: error: {}\n", m_prefix, message);
  if (m_status == 0 || status == 1) m_status = status;
}

void Diagnostics::report(std::string_view message) { *m_out << fmt::format("{}: {}\n", m_prefix, message); }

void Diagnostics::progress(std::string_view message) {
  *m_out << fmt::format("\r{}: {}", m_prefix, message) << std::flush;
}

void Diagnostics::end_progress() { *m_out << '\n'; }

}  // namespace mcg
