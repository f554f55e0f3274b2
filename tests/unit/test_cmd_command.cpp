// The command layer: a tool's exit status from its command and its diagnostics, and commands
// that take the tool's name from their Io instead of naming one.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cmd/command.hpp"
#include "cmd/design/analysis.hpp"
#include "cmd/fit/model.hpp"
#include "cmd/serial/registers.hpp"
#include "cmd/sweep/bode.hpp"
#include "cmd/sweep/generate.hpp"
#include "common/error.hpp"

namespace mcg::cmd {
namespace {

/// A subcommand that reports an error of `status` on the diagnostics and returns `returned`.
class Reporting final : public Command {
 public:
  int status = 0;
  int returned = 0;
  std::string name() const override { return "report"; }
  std::string help() const override { return "reports"; }
  void define(CLI::App& app) override { app.add_option("--status", status); }
  int run(Io& io) override {
    if (status != 0) io.diag.error("the numbers are not to be relied on", status);
    return returned;
  }
};

int run_main(Command& command, std::vector<std::string> args, Diagnostics& diag) {
  CLI::App app{"a tool", "tool"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  return main_of(app, static_cast<int>(argv.size()), argv.data(), diag, {&command});
}

TEST(CmdCommand, TheExitStatusIsTheCommandsOrElseTheDiagnostics) {
  std::ostringstream err;
  Diagnostics diag(err, "tool");
  Reporting command;
  EXPECT_EQ(run_main(command, {"tool", "report", "--status", "3"}, diag), 3);
  EXPECT_EQ(err.str(), "tool: error: the numbers are not to be relied on\n");
  Diagnostics quiet(err, "tool");
  Reporting partial;
  partial.returned = 4;
  EXPECT_EQ(run_main(partial, {"tool", "report"}, quiet), 4);
  Diagnostics clean(err, "tool");
  Reporting fine;
  EXPECT_EQ(run_main(fine, {"tool", "report"}, clean), 0);
}

TEST(CmdCommand, ResultsNameTheToolOfTheirIo) {
  std::istringstream in;
  std::ostringstream out;
  std::ostringstream err;
  Diagnostics diag(err, "prefix");
  Io io{in, out, diag, "some-tool"};
  Bode bode(false);
  bode.options.plant.plant = "1/(s+1)";
  bode.options.points = 2;
  EXPECT_EQ(bode.run(io), 0);
  EXPECT_NE(out.str().find("# source: some-tool "), std::string::npos) << out.str();
  EXPECT_EQ(out.str().find("mcg-"), std::string::npos) << out.str();
  EXPECT_EQ(err.str(), "");
}

TEST(CmdCommand, AParameterNameTheModelLacksPointsToTheToolsList) {
  std::istringstream in;
  std::ostringstream out;
  std::ostringstream err;
  Diagnostics diag(err, "prefix");
  Io io{in, out, diag, "some-tool"};
  FitModel model;
  model.options.files = {"-"};
  model.options.free = {"motor.bogus"};
  try {
    model.run(io);
    FAIL() << "an unknown parameter was fitted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "unknown parameter 'motor.bogus' (see some-tool model --list)");
  }
}

TEST(CmdCommand, SweepTablesAndResponsesNameTheToolOfTheirIo) {
  std::istringstream in;
  std::ostringstream table;
  std::ostringstream err;
  Diagnostics diag(err, "prefix");
  Io io{in, table, diag, "some-tool"};
  SweepGenerate step(signal::Generator::step);
  step.options.dt_s = 0.001;
  step.options.duration_s = 0.004;
  EXPECT_EQ(step.run(io), 0);
  EXPECT_NE(table.str().find("# source: some-tool "), std::string::npos) << table.str();
  EXPECT_EQ(table.str().find("mcg-"), std::string::npos) << table.str();

  // Uneven sampling: the response is written and the warning goes to the tool's diagnostics.
  const std::string path = ::testing::TempDir() + "cmd_uneven.csv";
  {
    std::ofstream file(path);
    file << "t,v,omega\n";
    for (int k = 0; k < 400; ++k)
      file << 0.001 * k + (k % 2 == 1 ? 0.0004 : 0.0) << "," << k % 3 << "," << k % 5 << "\n";
  }
  std::ostringstream response;
  Io bode_io{in, response, diag, "some-tool"};
  SweepBode bode;
  bode.options.input = path;
  EXPECT_EQ(bode.run(bode_io), 0);
  EXPECT_EQ(err.str().rfind("prefix: warning: " + path + ": uneven sampling", 0), 0u) << err.str();
  EXPECT_NE(response.str().find("# source: some-tool "), std::string::npos) << response.str();
  EXPECT_EQ(response.str().find("mcg-"), std::string::npos) << response.str();
}

TEST(CmdCommand, ASerialCommandWithoutAPortIsAUsageError) {
  std::istringstream in;
  std::ostringstream out;
  std::ostringstream err;
  Diagnostics diag(err, "prefix");
  Io io{in, out, diag, "some-tool"};
  link::LinkOptions line;
  SerialGet get(line);
  EXPECT_THROW(get.run(io), CLI::RequiredError);
  EXPECT_EQ(line.tool, "");
}

}  // namespace
}  // namespace mcg::cmd
