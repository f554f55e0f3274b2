// FdInput: a streambuf over a file descriptor that never waits for more than one byte.
#include "common/fd_input.hpp"

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "common/error.hpp"

namespace mcg {

namespace {
constexpr std::size_t k_buffer_bytes = 1 << 16;
}

FdInput::FdInput(int fd, std::string name) : m_fd(fd), m_name(std::move(name)), m_buffer(k_buffer_bytes) {}

std::size_t FdInput::read_some(char* dest, std::size_t count) {
  if (m_hook) {
    pollfd p{m_fd, POLLIN, 0};
    int ready = 0;
    do {
      ready = ::poll(&p, 1, 0);
    } while (ready < 0 && errno == EINTR);
    if (ready == 0) m_hook();
  }
  for (;;) {
    const ssize_t n = ::read(m_fd, dest, count);
    if (n >= 0) return static_cast<std::size_t>(n);
    if (errno != EINTR) fail("{}: read error: {}", m_name, std::strerror(errno));
  }
}

FdInput::int_type FdInput::underflow() {
  if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
  const std::size_t n = read_some(m_buffer.data(), m_buffer.size());
  if (n == 0) return traits_type::eof();
  setg(m_buffer.data(), m_buffer.data(), m_buffer.data() + n);
  return traits_type::to_int_type(*gptr());
}

std::streamsize FdInput::xsgetn(char* dest, std::streamsize count) {
  if (count <= 0) return 0;
  // What underflow() buffered goes first; otherwise one read straight into the caller's block.
  if (gptr() < egptr()) {
    const auto n = std::min<std::streamsize>(count, egptr() - gptr());
    std::memcpy(dest, gptr(), static_cast<std::size_t>(n));
    gbump(static_cast<int>(n));
    return n;
  }
  return static_cast<std::streamsize>(read_some(dest, static_cast<std::size_t>(count)));
}

}  // namespace mcg
