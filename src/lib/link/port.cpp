// Serial ports through libserialport, pseudo-terminals through termios; both waited on with poll.
#include "link/port.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <libserialport.h>
#include <poll.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string_view>

#include "common/poll_timeout.hpp"

namespace mcg::link {

namespace {

using Clock = std::chrono::steady_clock;

speed_t termios_speed(int baud) {
  switch (baud) {
    case 1200:
      return B1200;
    case 2400:
      return B2400;
    case 4800:
      return B4800;
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    default:
      fail("--baud: unsupported rate {} (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200)", baud);
  }
}

/// The shared part: an open descriptor, exclusive, waited on with poll.
class FdPort : public Port {
 public:
  FdPort(std::string name, int fd) : m_name(std::move(name)), m_fd(fd) {}

  const std::string& name() const override { return m_name; }

  std::size_t read_some(std::span<std::uint8_t> buf, double timeout_s) override {
    pollfd p{m_fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, poll_timeout_ms(timeout_s));
    if (ready < 0) {
      if (errno == EINTR) return 0;
      fail("{}: waiting for input: {}", m_name, std::strerror(errno));
    }
    if (ready == 0) return 0;
    if ((p.revents & POLLIN) == 0) vanished();
    const long n = raw_read(buf);
    if (n > 0) return static_cast<std::size_t>(n);
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) return 0;
    vanished();
  }

  void write_all(std::span<const std::uint8_t> bytes, double timeout_s) override {
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
    while (!bytes.empty()) {
      const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
      if (left <= 0.0) fail("{}: write timed out after {} s (is the line blocked?)", m_name, timeout_s);
      pollfd p{m_fd, POLLOUT, 0};
      const int ready = ::poll(&p, 1, poll_timeout_ms(left));
      if (ready < 0 && errno != EINTR) fail("{}: waiting to write: {}", m_name, std::strerror(errno));
      if (ready <= 0) continue;
      if ((p.revents & POLLOUT) == 0) vanished();
      const long n = raw_write(bytes);
      if (n < 0) {
        if (errno == EAGAIN || errno == EINTR) continue;
        vanished();
      }
      bytes = bytes.subspan(static_cast<std::size_t>(n));
    }
  }

  void discard_input() override { ::tcflush(m_fd, TCIFLUSH); }
  int poll_fd() const override { return m_fd; }

 protected:
  virtual long raw_read(std::span<std::uint8_t> buf) { return ::read(m_fd, buf.data(), buf.size()); }
  virtual long raw_write(std::span<const std::uint8_t> bytes) {
    return ::write(m_fd, bytes.data(), bytes.size());
  }

  /// Takes the advisory lock every mcg tool honours, and TIOCEXCL for the others.
  void make_exclusive() {
    if (::flock(m_fd, LOCK_EX | LOCK_NB) != 0) fail("{}", open_error_message(m_name, EBUSY));
    ::ioctl(m_fd, TIOCEXCL);
  }

  [[noreturn]] void vanished() const { throw PortVanished(fmt::format("{}: the port vanished", m_name)); }

  std::string m_name;
  int m_fd;
};

/// A pseudo-terminal or other tty libserialport does not know: termios directly.
class TtyPort final : public FdPort {
 public:
  TtyPort(const std::string& path, int baud) : FdPort(path, open_tty(path)) {
    try {
      make_exclusive();
      termios tio{};
      if (::tcgetattr(m_fd, &tio) != 0) fail("{}: not a serial port", path);
      ::cfmakeraw(&tio);
      tio.c_cflag |= CLOCAL | CREAD;
      tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS);
      tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
      tio.c_cc[VMIN] = 0;
      tio.c_cc[VTIME] = 0;
      const speed_t speed = termios_speed(baud);
      ::cfsetispeed(&tio, speed);
      ::cfsetospeed(&tio, speed);
      if (::tcsetattr(m_fd, TCSANOW, &tio) != 0) fail("{}: cannot configure: {}", path, std::strerror(errno));
    } catch (...) {
      ::close(m_fd);
      throw;
    }
  }
  ~TtyPort() override {
    // TIOCEXCL outlives this descriptor while the far end keeps the slave open: release it.
    ::ioctl(m_fd, TIOCNXCL);
    ::close(m_fd);
  }

 private:
  static int open_tty(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) fail("{}", open_error_message(path, errno));
    if (::isatty(fd) != 1) {
      ::close(fd);
      fail("{}: not a serial port", path);
    }
    return fd;
  }
};

/// A serial device enumerated by libserialport: opened and configured through it.
class SpPort final : public FdPort {
 public:
  SpPort(const std::string& path, sp_port* port, int baud) : FdPort(path, -1), m_port(port) {
    if (sp_open(m_port, SP_MODE_READ_WRITE) != SP_OK) {
      const int err = sp_last_error_code();
      sp_free_port(m_port);
      fail("{}", open_error_message(path, err));
    }
    try {
      sp_get_port_handle(m_port, &m_fd);
      make_exclusive();
      if (sp_set_baudrate(m_port, baud) != SP_OK || sp_set_bits(m_port, 8) != SP_OK ||
          sp_set_parity(m_port, SP_PARITY_NONE) != SP_OK || sp_set_stopbits(m_port, 1) != SP_OK ||
          sp_set_flowcontrol(m_port, SP_FLOWCONTROL_NONE) != SP_OK) {
        fail("{}: cannot set {} baud 8N1: {}", path, baud, sp_last_error_message());
      }
    } catch (...) {
      sp_close(m_port);
      sp_free_port(m_port);
      throw;
    }
  }
  ~SpPort() override {
    ::ioctl(m_fd, TIOCNXCL);
    sp_close(m_port);
    sp_free_port(m_port);
  }

  void discard_input() override { sp_flush(m_port, SP_BUF_INPUT); }

 protected:
  long raw_read(std::span<std::uint8_t> buf) override {
    const int n = sp_nonblocking_read(m_port, buf.data(), buf.size());
    if (n < 0) errno = sp_last_error_code();
    return n;
  }
  long raw_write(std::span<const std::uint8_t> bytes) override {
    const int n = sp_nonblocking_write(m_port, bytes.data(), bytes.size());
    if (n < 0) errno = sp_last_error_code();
    return n;
  }

 private:
  sp_port* m_port;
};

}  // namespace

std::string open_error_message(const std::string& path, int err) {
  switch (err) {
    case ENOENT:
    case ENODEV:
    case ENXIO:
      return fmt::format("{}: no such port (the list command shows the serial ports)", path);
    case EACCES:
    case EPERM:
      return fmt::format(
          "{}: permission denied (add your user to the 'dialout' group: sudo usermod -aG dialout $USER, "
          "then log in again)",
          path);
    case EBUSY:
    case EWOULDBLOCK:
      return fmt::format("{}: port busy (another program has it open)", path);
    default:
      return fmt::format("{}: cannot open: {}", path, std::strerror(err));
  }
}

std::unique_ptr<Port> open_port(const std::string& path, int baud) {
  termios_speed(baud);
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) fail("{}", open_error_message(path, errno));
  if (!S_ISCHR(st.st_mode)) fail("{}: not a serial port", path);
  sp_port* port = nullptr;
  if (sp_get_port_by_name(path.c_str(), &port) == SP_OK) return std::make_unique<SpPort>(path, port, baud);
  return std::make_unique<TtyPort>(path, baud);
}

std::vector<PortListing> list_ports() {
  sp_port** list = nullptr;
  if (sp_list_ports(&list) != SP_OK) fail("listing serial ports: {}", sp_last_error_message());
  std::vector<PortListing> out;
  for (sp_port** p = list; *p != nullptr; ++p) {
    PortListing item;
    item.name = sp_get_port_name(*p);
    const char* desc = sp_get_port_description(*p);
    item.description = desc != nullptr ? desc : "";
    if (sp_get_port_transport(*p) == SP_TRANSPORT_USB) {
      int vid = 0;
      int pid = 0;
      sp_get_port_usb_vid_pid(*p, &vid, &pid);
      const char* serial = sp_get_port_usb_serial(*p);
      item.description += fmt::format(" (USB {:04x}:{:04x}{}{})", vid, pid, serial != nullptr ? ", serial " : "",
                                      serial != nullptr ? serial : "");
    }
    out.push_back(std::move(item));
  }
  sp_free_port_list(list);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  return out;
}

namespace {

std::string runtime_dir() {
  const char* dir = std::getenv("XDG_RUNTIME_DIR");
  return (dir != nullptr && *dir != '\0') ? std::string(dir) : std::string("/tmp");
}

constexpr std::string_view k_entry_prefix = "mcg-board.";

}  // namespace

EmulatedPortEntry::EmulatedPortEntry(const std::string& link_path, const std::string& description)
    : m_file(fmt::format("{}/{}{}", runtime_dir(), k_entry_prefix, ::getpid())) {
  std::string path = link_path;
  if (!path.starts_with('/')) {
    if (char* cwd = ::getcwd(nullptr, 0)) {
      path = fmt::format("{}/{}", cwd, path.starts_with("./") ? path.substr(2) : path);
      std::free(cwd);
    }
  }
  // The entry is a convenience for `list`: a directory that takes no file leaves it out.
  if (std::FILE* f = std::fopen(m_file.c_str(), "w")) {
    std::fputs(fmt::format("{}\t{}\n", path, description).c_str(), f);
    std::fclose(f);
  } else {
    m_file.clear();
  }
}

EmulatedPortEntry::~EmulatedPortEntry() {
  if (!m_file.empty()) ::unlink(m_file.c_str());
}

std::vector<PortListing> emulated_ports() {
  std::vector<PortListing> out;
  const std::string dir = runtime_dir();
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return out;
  while (const dirent* e = ::readdir(d)) {
    const std::string_view name = e->d_name;
    if (!name.starts_with(k_entry_prefix)) continue;
    const std::string_view pid_text = name.substr(k_entry_prefix.size());
    int pid = 0;
    const auto [ptr, ec] = std::from_chars(pid_text.data(), pid_text.data() + pid_text.size(), pid);
    if (ec != std::errc() || ptr != pid_text.data() + pid_text.size() || pid <= 0) continue;
    if (::kill(pid, 0) != 0 && errno != EPERM) continue;  // its process is gone
    std::ifstream in(fmt::format("{}/{}", dir, name));
    std::string line;
    if (!std::getline(in, line)) continue;
    const auto tab = line.find('\t');
    if (tab == std::string::npos) continue;
    PortListing item{line.substr(0, tab), line.substr(tab + 1)};
    struct stat st {};
    if (::stat(item.name.c_str(), &st) != 0) continue;  // the link is gone
    out.push_back(std::move(item));
  }
  ::closedir(d);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  return out;
}

}  // namespace mcg::link
