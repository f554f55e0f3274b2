// The board's `# excitation:` line (see board_excitation.hpp).
#include "measurement/board_excitation.hpp"

#include <fmt/format.h>

#include <cmath>

#include "common/error.hpp"  // mcg::fail
#include "common/quote.hpp"
#include "config/ini.hpp"   // format_number
#include "table/table.hpp"  // parse_number

namespace mcg::measurement {

std::optional<double> BoardExcitation::value(std::string_view key) const {
  for (const auto& [k, v] : values) {
    if (k == key) return v;
  }
  return std::nullopt;
}

std::string format_board_excitation(const BoardExcitation& excitation) {
  std::string text = fmt::format("{} column={}", excitation.kind, excitation.column);
  for (const auto& [key, v] : excitation.values) text += fmt::format(" {}={}", key, config::format_number(v));
  return text;
}

std::optional<BoardExcitation> parse_board_excitation(std::string_view text, std::string_view where) {
  BoardExcitation out;
  std::size_t at = 0;
  bool first = true;
  while (at < text.size()) {
    const std::size_t end = std::min(text.find(' ', at), text.size());
    const std::string_view word = text.substr(at, end - at);
    at = end + 1;
    if (word.empty()) continue;
    if (first) {
      out.kind = std::string(word);
      first = false;
      continue;
    }
    const std::size_t eq = word.find('=');
    if (eq == std::string_view::npos) return std::nullopt;  // mcg-sweep's prose, not the board's form
    const std::string_view key = word.substr(0, eq);
    const std::string_view v = word.substr(eq + 1);
    if (key == "column") {
      out.column = std::string(v);
      continue;
    }
    double number = 0.0;
    if (!table::parse_number(v, number) || !std::isfinite(number)) {
      fail("{}: excitation: {} is not a number", where, quote(word));
    }
    out.values.emplace_back(std::string(key), number);
  }
  if (out.column.empty()) return std::nullopt;
  return out;
}

}  // namespace mcg::measurement
