// mcg-sweep bode on the metadata it trusts (sample_period, multisine_period_s,
// multisine_lines_hz, excitation_start_s, excitation_end_s, excitation_band_hz): the input's
// text is the metadata and header, followed by 64 rows of a fixed signal, evenly or unevenly
// sampled (the first byte picks). Every value that sizes work must be checked (ASan's
// allocation limit and UBSan's float-cast check catch one that is not).
#include "fuzz.hpp"
#include "signal/sweep.hpp"
#include "table/table.hpp"

#include <cmath>
#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const bool uneven = (data[0] & 1u) != 0;
  const bool lines = (data[0] & 2u) != 0;
  std::string text(mcg::fuzz::text_of(data + 1, size - 1));
  if (!text.empty() && text.back() != '\n') text += '\n';
  // Without a header of its own the input's last line is metadata: the fixed header follows.
  if (!text.starts_with("t,") && text.find("\nt,") == std::string::npos) text += "t,v,omega\n";
  for (int k = 0; k < 64; ++k) {
    const double t = uneven ? 0.001 * k + 0.0004 * (k % 3) : 0.001 * k;
    text += std::to_string(t) + "," + std::to_string(std::sin(0.7 * k)) + "," +
            std::to_string(std::cos(0.3 * k)) + "\n";
  }
  try {
    std::istringstream in(text);
    const mcg::table::Table tbl = mcg::table::read(in, "<fuzz>");
    mcg::signal::BodeOptions o;
    o.method = lines ? mcg::signal::BodeMethod::automatic : mcg::signal::BodeMethod::welch;
    std::ostringstream out;
    std::ostringstream warn;
    mcg::Diagnostics diag(warn, "bode");
    mcg::signal::bode(tbl, o, out, diag);
    for (const char c : warn.str()) {
      if (static_cast<unsigned char>(c) < 0x20 && c != '\n')
        mcg::fuzz::finding("a warning carries a control byte");
    }
  } catch (const mcg::Error& e) {
    mcg::fuzz::check_message(e);
  }
  return 0;
}
