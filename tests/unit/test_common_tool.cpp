// Usage errors name what is wrong: the unknown option or subcommand, with the nearest name.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "common/tool.hpp"

namespace mcg {
namespace {

TEST(CommonTool, NearestNameIsATypoAwayOrNone) {
  const std::vector<std::string> subs{"list", "get", "set", "load", "stream", "dump", "send", "serve"};
  EXPECT_EQ(nearest_name("strem", subs), "stream");
  EXPECT_EQ(nearest_name("stpe", {"step", "staircase", "chirp"}), "step");  // a swap is one edit
  EXPECT_EQ(nearest_name("gt", subs), "get");
  EXPECT_EQ(nearest_name("sned", subs), "send");
  EXPECT_EQ(nearest_name("xyzzy", subs), std::nullopt);
  EXPECT_EQ(nearest_name("ab", {"p"}), std::nullopt);  // not nearer than the name is long
}

// What tool_main prints after "mcg-TOOL: error: " for the arguments given.
std::string usage_of(std::vector<std::string> args) {
  CLI::App app{"test", "mcg-test"};
  app.require_subcommand(1);
  double pm = 0;
  int seconds = 0;
  app.add_option("--port", pm, "port");
  auto* stream = app.add_subcommand("stream", "stream");
  stream->add_option("--seconds", seconds, "seconds")->check(CLI::Range(0, 10));
  app.add_subcommand("get", "get");
  std::vector<char*> argv{const_cast<char*>("mcg-test")};
  for (auto& a : args) argv.push_back(a.data());
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const CLI::ParseError& e) {
    return usage_message(app, e);
  }
  return "(parsed)";
}

TEST(CommonTool, UsageMessagesNameTheArgument) {
  EXPECT_EQ(usage_of({"strem"}), "unknown subcommand 'strem': did you mean 'stream'?");
  EXPECT_EQ(usage_of({"--port", "1", "zap"}), "unknown subcommand 'zap': not one of stream, get");
  // CLI11 reports the missing subcommand first; the unknown option is the real fault.
  EXPECT_EQ(usage_of({"--bogus"}), "unknown option '--bogus'");
  EXPECT_EQ(usage_of({"--prot", "1", "get"}), "unknown option '--prot': did you mean '--port'?");
  EXPECT_EQ(usage_of({"stream", "--secnds=3"}), "unknown option '--secnds': did you mean '--seconds'?");
  EXPECT_EQ(usage_of({"stream", "extra"}), "unexpected argument 'extra'");
  EXPECT_EQ(usage_of({"stream", "--seconds", "11"}), "--seconds: Value 11 not in range 0 to 10");
  EXPECT_EQ(usage_of({}), "A subcommand is required");
  EXPECT_EQ(usage_of({"get"}), "(parsed)");
}

}  // namespace
}  // namespace mcg
