// FdInput hands over what a pipe holds without waiting to fill a block, and says when it waits.
#include <gtest/gtest.h>

#include <unistd.h>

#include <string>

#include "common/error.hpp"
#include "common/fd_input.hpp"

namespace mcg {
namespace {

struct Pipe {
  int fd[2] = {-1, -1};
  Pipe() { EXPECT_EQ(::pipe(fd), 0); }
  ~Pipe() {
    for (int f : fd) {
      if (f >= 0) ::close(f);
    }
  }
  void write(const std::string& s) const { ASSERT_EQ(::write(fd[1], s.data(), s.size()), static_cast<ssize_t>(s.size())); }
  void close_write() {
    ::close(fd[1]);
    fd[1] = -1;
  }
};

TEST(CommonFdInput, ReturnsWhatArrivedWithoutFillingTheBlock) {
  Pipe p;
  FdInput in(p.fd[0], "<pipe>");
  int waits = 0;
  in.before_wait([&] { ++waits; });
  p.write("t,v\n0,1\n");
  char block[1 << 16];
  EXPECT_EQ(in.sgetn(block, sizeof block), 8);
  EXPECT_EQ(std::string(block, 8), "t,v\n0,1\n");
  EXPECT_EQ(waits, 0);  // the data was there: no wait announced
  p.write("0.1,2\n");
  p.close_write();
  EXPECT_EQ(in.sgetn(block, sizeof block), 6);
  EXPECT_EQ(in.sgetn(block, sizeof block), 0);  // end of input: poll says ready, no wait
  EXPECT_EQ(waits, 0);
}

TEST(CommonFdInput, CallsTheHookBeforeItWaits) {
  Pipe p;
  FdInput in(p.fd[0], "<pipe>");
  int waits = 0;
  in.before_wait([&] {
    ++waits;
    p.write("x");  // the hook runs before the read that would block
  });
  char c = 0;
  EXPECT_EQ(in.sgetn(&c, 1), 1);
  EXPECT_EQ(c, 'x');
  EXPECT_EQ(waits, 1);
}

TEST(CommonFdInput, AReadErrorNamesTheInput) {
  FdInput in(-1, "<stdin>");
  char c = 0;
  try {
    in.sgetn(&c, 1);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "<stdin>: read error: Bad file descriptor");
  }
}

}  // namespace
}  // namespace mcg
