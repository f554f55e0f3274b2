// Input from a file descriptor that hands over what has arrived instead of waiting to fill a
// block, so a filter can answer each row of a live pipe as it comes.
#pragma once

#include <functional>
#include <streambuf>
#include <string>
#include <vector>

namespace mcg {

/// A read-only streambuf over `fd`: sgetn() returns the bytes that are there (at least one,
/// waiting for them if none are), 0 at the end of input. Before it would wait, it calls the
/// hook set by before_wait() (a filter flushes its output there: the input paused).
/// A read error throws mcg::Error "<name>: read error: ...".
class FdInput : public std::streambuf {
 public:
  FdInput(int fd, std::string name);

  void before_wait(std::function<void()> hook) { m_hook = std::move(hook); }

 protected:
  int_type underflow() override;
  std::streamsize xsgetn(char* dest, std::streamsize count) override;

 private:
  /// One read(2) of up to `count` bytes into `dest`, calling the hook first when nothing is
  /// ready; 0 at the end of input.
  std::size_t read_some(char* dest, std::size_t count);

  int m_fd;
  std::string m_name;
  std::function<void()> m_hook;
  std::vector<char> m_buffer;
};

}  // namespace mcg
