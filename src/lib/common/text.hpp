// Text helpers every reader shares.
#pragma once

#include <string_view>

namespace mcg {

/// `s` without leading and trailing blanks (spaces and tabs).
constexpr std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

/// trim() for one line of a file that may end in CRLF: a trailing '\r' goes with the blanks.
constexpr std::string_view trim_line(std::string_view s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return trim(s);
}

}  // namespace mcg
