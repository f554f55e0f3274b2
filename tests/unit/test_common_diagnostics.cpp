// Diagnostics: the prefix and kind of every message, and the exit status the errors carry.
#include <gtest/gtest.h>

#include <sstream>

#include "common/diagnostics.hpp"

namespace mcg {
namespace {

TEST(CommonDiagnostics, PrefixesEachKindOfMessage) {
  std::ostringstream out;
  Diagnostics diag(out, "tool");
  diag.warning("w");
  diag.note("n");
  diag.report("r");
  diag.progress("1/2");
  diag.end_progress();
  EXPECT_EQ(out.str(), "tool: warning: w\ntool: note: n\ntool: r\n\rtool: 1/2\n");
  EXPECT_EQ(diag.status(), 0);
}

TEST(CommonDiagnostics, AnInputErrorOutranksAVerdictStatus) {
  std::ostringstream out;
  Diagnostics diag(out, "tool");
  diag.error("a.csv: did not converge", k_untrustworthy_status);
  EXPECT_EQ(diag.status(), k_untrustworthy_status);
  diag.error("b.csv: cannot open");
  EXPECT_EQ(diag.status(), 1);
  diag.error("c.csv: did not converge", k_untrustworthy_status);
  EXPECT_EQ(diag.status(), 1);
  EXPECT_EQ(out.str(),
            "tool: error: a.csv: did not converge\ntool: error: b.csv: cannot open\n"
            "tool: error: c.csv: did not converge\n");
}

}  // namespace
}  // namespace mcg
