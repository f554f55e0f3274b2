// Pseudo-terminal creation with a symbolic link.
#include "link/pty.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>

#include "common/error.hpp"  // mcg::fail

namespace mcg::link {

PtyLink::PtyLink(const std::string& link_path) : m_link(link_path) {
  m_master = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (m_master < 0) fail("{}: cannot create a pseudo-terminal: {}", link_path, std::strerror(errno));
  try {
    if (::grantpt(m_master) != 0 || ::unlockpt(m_master) != 0) {
      fail("{}: cannot unlock the pseudo-terminal: {}", link_path, std::strerror(errno));
    }
    const char* name = ::ptsname(m_master);
    if (name == nullptr) fail("{}: no pseudo-terminal name: {}", link_path, std::strerror(errno));
    m_slave_path = name;
    m_slave = ::open(m_slave_path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (m_slave < 0) fail("{}: cannot open {}: {}", link_path, m_slave_path, std::strerror(errno));
    termios tio{};
    ::tcgetattr(m_slave, &tio);
    ::cfmakeraw(&tio);
    tio.c_cflag |= CLOCAL | CREAD;
    tio.c_cc[VMIN] = 0;
    tio.c_cc[VTIME] = 0;
    ::tcsetattr(m_slave, TCSANOW, &tio);

    struct stat st {};
    if (::lstat(link_path.c_str(), &st) == 0) {
      char target[256] = {};
      const ssize_t n = S_ISLNK(st.st_mode) ? ::readlink(link_path.c_str(), target, sizeof target - 1) : -1;
      if (n <= 0 || std::strncmp(target, "/dev/pts/", 9) != 0) {
        fail("{}: exists and is not a link to a pseudo-terminal", link_path);
      }
      ::unlink(link_path.c_str());
    }
    if (::symlink(m_slave_path.c_str(), link_path.c_str()) != 0) {
      fail("{}: cannot create the link: {}", link_path, std::strerror(errno));
    }
  } catch (...) {
    if (m_slave >= 0) ::close(m_slave);
    ::close(m_master);
    throw;
  }
}

void PtyLink::close() {
  if (m_master < 0) return;
  ::unlink(m_link.c_str());
  ::close(m_slave);
  ::close(m_master);
  m_slave = -1;
  m_master = -1;
}

PtyLink::~PtyLink() { close(); }

}  // namespace mcg::link
