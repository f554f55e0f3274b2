// Unit tests of the port owner's rule for the board's shadow set: one client stages the
// controller's set at a time, and a set its writer left or abandoned is discarded, never
// committed half-written. The board is a line that accepts every write.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>

#include "link/frame.hpp"
#include "link/owner.hpp"
#include "link/registers.hpp"
#include "link/session.hpp"
#include "mcg_protocol.h"
#include "test_support_error.hpp"

namespace mcg::link {
namespace {

using Bytes = std::vector<std::uint8_t>;

/// A board that answers every write OK with the value written, and records the writes.
class AcceptingBoard : public Port {
 public:
  const std::string& name() const override { return m_name; }
  std::size_t read_some(std::span<std::uint8_t> buf, double timeout_s) override {
    {
      std::lock_guard lock(m_mutex);
      if (!m_out.empty()) {
        const std::size_t n = std::min(buf.size(), m_out.size());
        std::copy(m_out.begin(), m_out.begin() + static_cast<std::ptrdiff_t>(n), buf.begin());
        m_out.erase(m_out.begin(), m_out.begin() + static_cast<std::ptrdiff_t>(n));
        return n;
      }
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(std::min(timeout_s, 0.002)));
    return 0;
  }
  void write_all(std::span<const std::uint8_t> bytes, double) override {
    std::vector<Frame> frames;
    m_decoder.feed(bytes, 0.0, frames);
    std::lock_guard lock(m_mutex);
    for (const Frame& f : frames) {
      if (f.cmd != MCG_CMD_WRITE || f.payload.size() != 3) continue;
      m_writes.push_back(f.payload);
      const Bytes reply{MCG_ST_OK, f.payload[0], f.payload[1], f.payload[2]};
      const Bytes bytes_out = encode(MCG_CMD_WRITE | MCG_REPLY_BIT, reply);
      m_out.insert(m_out.end(), bytes_out.begin(), bytes_out.end());
    }
  }
  void discard_input() override {}
  std::vector<Bytes> writes() {
    std::lock_guard lock(m_mutex);
    return m_writes;
  }

 private:
  std::mutex m_mutex;
  Decoder m_decoder;
  Bytes m_out;
  std::vector<Bytes> m_writes;
  // The owner's socket is named after the port: one per test process, since ctest runs the
  // tests of this suite side by side in one runtime directory.
  std::string m_name = "staging-test-board-" + std::to_string(::getpid());
};

class LinkOwner : public ::testing::Test {
 protected:
  void SetUp() override {
    ::setenv("XDG_RUNTIME_DIR", ::testing::TempDir().c_str(), 1);
    auto board = std::make_unique<AcceptingBoard>();
    m_board = board.get();
    m_owner = std::make_unique<PortOwner>(std::move(board));
  }
  std::unique_ptr<Port> client() { return connect_owner(m_board->name()); }
  static SessionOptions quick() {
    SessionOptions o;
    o.reply_timeout_s = 0.2;
    return o;
  }
  AcceptingBoard* m_board = nullptr;
  std::unique_ptr<PortOwner> m_owner;
};

std::uint8_t status_of_write(Session& s, const RegisterInfo& reg, std::int16_t raw) {
  try {
    s.write(reg, raw);
  } catch (const Refused& e) {
    return e.status();
  }
  return MCG_ST_OK;
}

TEST_F(LinkOwner, OneClientStagesAtATime) {
  const RegisterInfo& commit = require_register("commit");
  const RegisterInfo& b0 = require_register("b0");
  auto port_a = client();
  auto port_b = client();
  ASSERT_TRUE(port_a && port_b);
  Session a(*port_a, quick());
  Session b(*port_b, quick());
  EXPECT_EQ(status_of_write(a, commit, 0), MCG_ST_OK);
  EXPECT_EQ(status_of_write(a, b0, 100), MCG_ST_OK);
  // While a's set is staged, b may neither begin its own, write into a's, nor commit it.
  EXPECT_EQ(status_of_write(b, commit, 0), MCG_ST_BUSY);
  EXPECT_EQ(status_of_write(b, b0, 200), MCG_ST_BUSY);
  EXPECT_EQ(status_of_write(b, commit, 1), MCG_ST_BUSY);
  // Registers outside the controller's set are anyone's.
  EXPECT_EQ(status_of_write(b, require_register("rpm_cmd"), 300), MCG_ST_OK);
  EXPECT_EQ(status_of_write(a, commit, 1), MCG_ST_OK);
  EXPECT_EQ(status_of_write(b, commit, 0), MCG_ST_OK);
  EXPECT_EQ(status_of_write(b, b0, 200), MCG_ST_OK);
  EXPECT_EQ(status_of_write(b, commit, 1), MCG_ST_OK);
  const std::vector<Bytes> expected{
      {commit.id, 0, 0}, {b0.id, 100, 0},   {require_register("rpm_cmd").id, 44, 1},
      {commit.id, 1, 0}, {commit.id, 0, 0}, {b0.id, 200, 0},
      {commit.id, 1, 0}};
  EXPECT_EQ(m_board->writes(), expected);
}

TEST_F(LinkOwner, ASetItsWriterLeftIsDiscardedAndFreed) {
  const RegisterInfo& commit = require_register("commit");
  const RegisterInfo& b0 = require_register("b0");
  auto port_b = client();
  ASSERT_TRUE(port_b);
  Session b(*port_b, quick());
  {
    auto port_a = client();
    ASSERT_TRUE(port_a);
    Session a(*port_a, quick());
    EXPECT_EQ(status_of_write(a, b0, 100), MCG_ST_OK);
  }
  // The owner notices a's end within its poll; b's discard may meet the hold once.
  std::uint8_t st = MCG_ST_BUSY;
  for (int i = 0; i < 50 && st == MCG_ST_BUSY; ++i) {
    st = status_of_write(b, commit, 0);
    if (st == MCG_ST_BUSY) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(st, MCG_ST_OK);
  const std::vector<Bytes> expected{{b0.id, 100, 0}, {commit.id, 0, 0}, {commit.id, 0, 0}};
  EXPECT_EQ(m_board->writes(), expected);  // the owner's discard of a's set, then b's
}

TEST_F(LinkOwner, ASilentStagerLosesItsSetAndCannotCommitTheRest) {
  const RegisterInfo& commit = require_register("commit");
  const RegisterInfo& b0 = require_register("b0");
  const RegisterInfo& b1 = require_register("b1");
  auto port_a = client();
  ASSERT_TRUE(port_a);
  Session a(*port_a, quick());
  EXPECT_EQ(status_of_write(a, commit, 0), MCG_ST_OK);
  EXPECT_EQ(status_of_write(a, b0, 100), MCG_ST_OK);
  std::this_thread::sleep_for(std::chrono::duration<double>(k_stage_idle_s + 0.3));
  EXPECT_EQ(status_of_write(a, b1, 50), MCG_ST_BUSY);
  EXPECT_EQ(status_of_write(a, commit, 1), MCG_ST_BUSY);
  EXPECT_EQ(status_of_write(a, commit, 0), MCG_ST_OK);  // begins afresh
  const std::vector<Bytes> expected{{commit.id, 0, 0}, {b0.id, 100, 0}, {commit.id, 0, 0}, {commit.id, 0, 0}};
  EXPECT_EQ(m_board->writes(), expected);
}

}  // namespace
}  // namespace mcg::link
