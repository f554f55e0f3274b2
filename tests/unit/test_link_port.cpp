// Unit tests of ports on real pseudo-terminals: bounded reads, exclusivity, the line vanishing,
// and the open errors' wording.
#include "link/port.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <functional>
#include <string>

#include "link/pty.hpp"
#include "test_support_error.hpp"

namespace mcg::link {
namespace {

std::string temp_link(const char* name) {
  return ::testing::TempDir() + "mcg_port_" + std::to_string(::getpid()) + "_" + name;
}

using test::error_of;

TEST(LinkPort, OpenErrorsSayWhatToDo) {
  EXPECT_EQ(open_error_message("/dev/ttyUSB0", EACCES),
            "/dev/ttyUSB0: permission denied (add your user to the 'dialout' group: sudo usermod -aG dialout $USER, "
            "then log in again)");
  EXPECT_EQ(open_error_message("/dev/ttyUSB0", ENOENT),
            "/dev/ttyUSB0: no such port (the list command shows the serial ports)");
  EXPECT_EQ(open_error_message("/dev/ttyUSB0", EBUSY), "/dev/ttyUSB0: port busy (another program has it open)");
  EXPECT_EQ(error_of([] { open_port("/dev/null", 9600); }), "/dev/null: not a serial port");
  EXPECT_EQ(error_of([] { open_port("/dev/null", 1000); }),
            "--baud: unsupported rate 1000 (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200)");
}

TEST(LinkPort, BytesBothWaysAndBoundedWaits) {
  const std::string path = temp_link("a");
  PtyLink pty(path);
  auto port = open_port(path, 9600);
  const std::uint8_t out[] = {0xA5, 0x00, 0x18, 0x0D, 0x0A, 0xFF};  // ^X, CR, LF: raw, untouched
  port->write_all(out, 1.0);
  std::uint8_t got[16] = {};
  std::size_t n = 0;
  for (int i = 0; i < 100 && n < sizeof out; ++i) {
    const ssize_t r = ::read(pty.fd(), got + n, sizeof got - n);
    if (r > 0) n += static_cast<std::size_t>(r);
    ::usleep(1000);
  }
  ASSERT_EQ(n, sizeof out);
  EXPECT_EQ(std::vector<std::uint8_t>(got, got + n), std::vector<std::uint8_t>(out, out + sizeof out));
  ASSERT_EQ(::write(pty.fd(), out, sizeof out), static_cast<ssize_t>(sizeof out));
  std::uint8_t back[16] = {};
  EXPECT_EQ(port->read_some(back, 1.0), sizeof out);
  EXPECT_EQ(back[2], 0x18);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(port->read_some(back, 0.05), 0u);
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GE(waited, 0.04);
  EXPECT_LT(waited, 1.0);
}

TEST(LinkPort, SecondOpenIsBusyUntilTheFirstCloses) {
  const std::string path = temp_link("b");
  PtyLink pty(path);
  {
    auto first = open_port(path, 9600);
    EXPECT_EQ(error_of([&] { open_port(path, 9600); }), path + ": port busy (another program has it open)");
  }
  EXPECT_NO_THROW(open_port(path, 9600));
}

TEST(LinkPort, ClosedLineVanishes) {
  const std::string path = temp_link("c");
  PtyLink pty(path);
  auto port = open_port(path, 9600);
  pty.close();
  std::uint8_t buf[8];
  EXPECT_THROW(port->read_some(buf, 1.0), PortVanished);
  EXPECT_EQ(::access(path.c_str(), F_OK), -1);  // the link is gone too
}

TEST(LinkPort, StaleLinkIsReplacedOtherFilesAreNot) {
  const std::string path = temp_link("d");
  ASSERT_EQ(::symlink("/dev/pts/999999", path.c_str()), 0);
  { PtyLink pty(path); }
  const std::string file = temp_link("e");
  FILE* f = std::fopen(file.c_str(), "w");
  std::fclose(f);
  EXPECT_EQ(error_of([&] { PtyLink pty(file); }), file + ": exists and is not a link to a pseudo-terminal");
  std::remove(file.c_str());
}

}  // namespace
}  // namespace mcg::link
