// Margins against the closed-loop poles: a loop's stable verdict (poles with their rounding
// bound) must agree with its stable gain ranges (exact boundary gains, each range probed) on
// where K = 1 lies, whenever both decide.
#include "fuzz.hpp"
#include "linsys/analysis.hpp"
#include "linsys/parse.hpp"

#include <algorithm>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(mcg::fuzz::text_of(data, size));
  mcg::linsys::Tf g;
  try {
    g = mcg::linsys::parse_tf(text, "--plant").tf;
    if (g.discrete()) {
      g.dt_s = 0.001;
      g = mcg::linsys::fold_delay(g, "--plant");
    }
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
    return 0;
  }
  // A continuous delay's verdict is defined by the ranges themselves; a loop of high degree
  // makes each probe an eigenvalue problem: both outside what this harness checks.
  if (g.delay_s != 0.0 || !g.proper() || mcg::linsys::degree(mcg::linsys::trim(g.den)) > 24) return 0;
  bool stable = false;
  std::vector<mcg::linsys::GainRange> ranges;
  try {
    stable = mcg::linsys::closed_loop_stable(g);
    ranges = mcg::linsys::stable_gain_ranges(g);
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
    return 0;
  }
  // K = 1 on a boundary gain (to rounding) is neither side: no verdict to compare.
  for (const auto& r : ranges) {
    for (const double k : {r.k_low, r.k_high}) {
      if (std::abs(k - 1.0) < 1e-6) return 0;
    }
  }
  const bool in_range =
      std::any_of(ranges.begin(), ranges.end(), [](const auto& r) { return r.k_low < 1.0 && 1.0 < r.k_high; });
  if (stable != in_range) mcg::fuzz::finding("the stable verdict disagrees with the stable gain ranges at K = 1");
  return 0;
}
