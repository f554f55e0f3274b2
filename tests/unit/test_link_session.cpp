// Unit tests of the session's rules: version check, retries, board error reports, stale
// answers, the messages for a silent or garbled line. The far end is a scripted line.
#include "link/session.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <thread>

#include "common/error.hpp"
#include "link/frame.hpp"
#include "mcg_protocol.h"
#include "test_support_error.hpp"

namespace mcg::link {
namespace {

using Bytes = std::vector<std::uint8_t>;

/// A line whose far end answers each request frame with the bytes `answer` returns.
class ScriptedLine : public Port {
 public:
  explicit ScriptedLine(std::function<Bytes(const Frame&, int)> answer) : m_answer(std::move(answer)) {}
  const std::string& name() const override { return m_name; }
  std::size_t read_some(std::span<std::uint8_t> buf, double timeout_s) override {
    if (m_out.empty()) {
      std::this_thread::sleep_for(std::chrono::duration<double>(std::min(timeout_s, 0.002)));
      return 0;
    }
    const std::size_t n = std::min(buf.size(), m_out.size());
    std::copy(m_out.begin(), m_out.begin() + static_cast<std::ptrdiff_t>(n), buf.begin());
    m_out.erase(m_out.begin(), m_out.begin() + static_cast<std::ptrdiff_t>(n));
    return n;
  }
  void write_all(std::span<const std::uint8_t> bytes, double) override {
    std::vector<Frame> frames;
    m_decoder.feed(bytes, 0.0, frames);
    for (const Frame& f : frames) {
      const Bytes reply = m_answer(f, m_requests++);
      m_out.insert(m_out.end(), reply.begin(), reply.end());
    }
  }
  void discard_input() override { m_out.clear(); }
  int requests() const { return m_requests; }

 private:
  std::function<Bytes(const Frame&, int)> m_answer;
  Decoder m_decoder;
  Bytes m_out;
  int m_requests = 0;
  std::string m_name = "line";
};

Bytes version_answer(unsigned protocol) {
  return encode(MCG_CMD_VERSION | MCG_REPLY_BIT, Bytes{MCG_ST_OK, static_cast<std::uint8_t>(protocol), 0, 9, 0, MCG_BOARD_C515});
}

using test::error_of;

SessionOptions quick() {
  SessionOptions o;
  o.reply_timeout_s = 0.02;
  return o;
}

TEST(LinkSession, WrongProtocolIsRefused) {
  ScriptedLine line([](const Frame&, int) { return version_answer(MCG_PROTOCOL_VERSION + 1); });
  Session s(line, quick());
  EXPECT_EQ(
      error_of([&] { s.hello(); }),
      "line: wrong firmware: it speaks protocol 6 (firmware 0.9.0 on c515), the host speaks protocol 5");
}

TEST(LinkSession, SilenceIsNothingAnsweringAfterEveryTry) {
  ScriptedLine line([](const Frame&, int) { return Bytes{}; });
  Session s(line, quick());
  EXPECT_EQ(error_of([&] { s.hello(); }),
            "line: nothing answers the version request after 3 tries (board off, not connected, or not running the "
            "mcg firmware?)");
  EXPECT_EQ(line.requests(), 3);
}

TEST(LinkSession, GarbleSuggestsTheBaudRate) {
  ScriptedLine line([](const Frame&, int) { return Bytes{0xA5, 0x03, 0x81, 0x00, 0x01, 0x02, 0x77, 0x66, 0xF0}; });
  Session s(line, quick());
  EXPECT_EQ(error_of([&] { s.hello(); }),
            "line: nothing answers the version request: only garbled bytes arrive (wrong --baud? not the mcg "
            "firmware?)");
}

TEST(LinkSession, BoardErrorReportMeansSendAgain) {
  // The board says it dropped a damaged frame: the request goes again at once.
  ScriptedLine line([](const Frame&, int n) {
    return n == 0 ? encode(MCG_MSG_ERROR, Bytes{MCG_ST_BAD_CRC}) : version_answer(MCG_PROTOCOL_VERSION);
  });
  Session s(line, quick());
  EXPECT_EQ(s.hello().board, MCG_BOARD_C515);
  EXPECT_EQ(line.requests(), 2);
}

TEST(LinkSession, StaleAnswerForAnotherRegisterIsIgnored) {
  ScriptedLine line([](const Frame& f, int) {
    if (f.cmd != MCG_CMD_READ) return version_answer(MCG_PROTOCOL_VERSION);
    Bytes out = encode(MCG_CMD_READ | MCG_REPLY_BIT, Bytes{MCG_ST_OK, 0x13, 0x10, 0x00});  // late answer, rpm
    const Bytes right = encode(MCG_CMD_READ | MCG_REPLY_BIT, Bytes{MCG_ST_OK, f.payload[0], 0xA4, 0x01});
    out.insert(out.end(), right.begin(), right.end());
    return out;
  });
  Session s(line, quick());
  RegisterInfo rpm_cmd{"rpm_cmd", MCG_REG_RPM_CMD, Unit::Rpm, true, 120, 720, 420, ""};
  EXPECT_EQ(s.read(rpm_cmd), 420);
}

TEST(LinkSession, RefusalCarriesTheBoardsReason) {
  ScriptedLine line([](const Frame& f, int) {
    return encode(static_cast<std::uint8_t>(f.cmd | MCG_REPLY_BIT), Bytes{MCG_ST_BUSY});
  });
  Session s(line, quick());
  EXPECT_EQ(error_of([&] { s.request(MCG_CMD_LOG_START, {}, "starting the log"); }),
            "line: starting the log: board busy (log recording, dump, sequence playing, or a set another "
            "writer staged)");
  EXPECT_EQ(line.requests(), 1);  // a refusal is an answer: not sent again
}

TEST(LinkSession, StreamBlocksDuringARequestAreKept) {
  ScriptedLine line([](const Frame&, int) {
    Bytes out = encode(MCG_MSG_STREAM, Bytes(MCG_STREAM_PAYLOAD, 7));
    const Bytes v = version_answer(MCG_PROTOCOL_VERSION);
    out.insert(out.end(), v.begin(), v.end());
    return out;
  });
  Session s(line, quick());
  s.request(MCG_CMD_VERSION, {}, "version");
  const auto f = s.receive(0.01);
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->cmd, MCG_MSG_STREAM);
}

}  // namespace
}  // namespace mcg::link
