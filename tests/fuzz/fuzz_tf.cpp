// Transfer-function text (the s/z parser) through margins and every c2d method.
#include "fuzz.hpp"
#include "linsys/analysis.hpp"
#include "linsys/c2d.hpp"
#include "linsys/parse.hpp"

#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // No size cap: the parser's own limits (k_max_tf_chars, k_max_tf_depth) must hold at any size.
  const std::string text(mcg::fuzz::text_of(data, size));
  mcg::linsys::Tf g;
  try {
    g = mcg::linsys::parse_tf(text, "--plant").tf;
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
    return 0;
  }
  if (mcg::linsys::degree(mcg::linsys::trim(g.den)) > mcg::linsys::k_max_degree) {
    mcg::fuzz::finding("the parser let a degree above the limit through");
  }
  if (g.discrete()) {
    g.dt_s = 0.001;
    try {
      g = mcg::linsys::fold_delay(g, "--plant");
    } catch (const mcg::Error& e) {
      mcg::fuzz::check_message(e);
      return 0;
    }
  }
  try {
    (void)mcg::linsys::margins(g);
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
  }
  // c2d costs O(n^4) (an LU per point of n + 1); beyond degree 32 it only slows the search.
  if (g.discrete() || mcg::linsys::degree(mcg::linsys::trim(g.den)) > 32) return 0;
  using mcg::linsys::C2dMethod;
  for (C2dMethod m : {C2dMethod::zoh, C2dMethod::foh, C2dMethod::tustin, C2dMethod::matched, C2dMethod::impulse}) {
    try {
      const mcg::linsys::Tf h = mcg::linsys::c2d(g, 0.001, m, 0.0, "--plant");
      if (mcg::linsys::degree(mcg::linsys::trim(h.den)) > mcg::linsys::k_max_degree) {
        mcg::fuzz::finding("c2d made a degree above the limit");
      }
    } catch (const mcg::Error& e) {
      mcg::fuzz::check_message(e);
    }
  }
  return 0;
}
