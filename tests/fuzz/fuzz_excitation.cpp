// mcg-sweep's generators on options their ranges accept (the CLI11 ranges of mcg-sweep.cpp):
// each option drawn from the input's bytes over its range, log-uniformly where the range spans
// decades. A table is written, or one line says which options ask too much; nothing allocates
// more than k_max_rows rows (ASan's allocation limit) or computes without bound (the timeout).
#include "fuzz.hpp"
#include "signal/excitation.hpp"
#include "signal/sweep.hpp"

#include <cmath>
#include <cstring>
#include <ostream>
#include <streambuf>
#include <string>

namespace {

/// Counts the lines written and drops them; past k_sink_lines it fails as a full disk would
/// (the Writer's error), so that a large table allowed costs its allocation, not its printing.
constexpr std::size_t k_sink_lines = 100000;

class LineCounter : public std::streambuf {
 public:
  std::size_t lines = 0;

 protected:
  int_type overflow(int_type c) override {
    if (lines > k_sink_lines) return traits_type::eof();
    if (c == '\n') ++lines;
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    if (lines > k_sink_lines) return 0;
    for (std::streamsize i = 0; i < n; ++i) {
      if (s[i] == '\n') ++lines;
    }
    return n;
  }
};

/// Reads the input's bytes as draws; past the end every draw is 0.
class Draws {
 public:
  Draws(const std::uint8_t* data, std::size_t size) : m_data(data), m_size(size) {}
  double unit() {
    std::uint16_t v = 0;
    for (int k = 0; k < 2; ++k)
      v = static_cast<std::uint16_t>((unsigned{v} << 8u) | (m_pos < m_size ? m_data[m_pos++] : 0u));
    return static_cast<double>(v) / 65535.0;
  }
  double log_range(double lo, double hi) { return lo * std::pow(hi / lo, unit()); }
  double range(double lo, double hi) { return lo + (hi - lo) * unit(); }
  int int_range(int lo, int hi) { return lo + static_cast<int>(std::floor(unit() * (hi - lo) + 0.5)); }
  bool flag() { return unit() >= 0.5; }

 private:
  const std::uint8_t* m_data;
  std::size_t m_size;
  std::size_t m_pos = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using mcg::signal::Generator;
  Draws d(data, size);
  const auto generator = static_cast<Generator>(d.int_range(0, 5));
  mcg::signal::GeneratorOptions o;
  o.dt_s = d.log_range(1e-6, 10.0);
  if (d.flag()) o.duration_s = d.log_range(1e-6, 1e6);
  o.at_s = d.flag() ? d.log_range(1e-6, 1e6) : 0.0;
  o.steps = d.int_range(1, 100000);
  o.hold_s = d.log_range(1e-6, 1e6);
  o.settle_s = d.flag() ? d.log_range(1e-6, 1e6) : 0.0;
  o.f0_hz = d.log_range(1e-6, 1e6);
  o.f1_hz = d.log_range(1e-6, 1e6);
  o.lines = d.int_range(1, 100000);
  if (d.flag()) o.period_s = d.log_range(1e-6, 1e6);
  o.order = d.int_range(mcg::signal::k_prbs_min_order, mcg::signal::k_prbs_max_order);
  if (d.flag()) o.clock_s = d.log_range(1e-6, 1e3);
  o.amp = d.range(0.0, 1e9);
  o.phases = d.flag() ? "schroeder" : "random";
  LineCounter sink;
  std::ostream out(&sink);
  try {
    mcg::signal::generate(generator, o, out);
    if (sink.lines > mcg::signal::k_max_rows + 64) mcg::fuzz::finding("more rows than k_max_rows");
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
  }
  return 0;
}
