// Shared by the fuzz harnesses: the libFuzzer entry point and the one rule they all check.
#pragma once

#include "common/error.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace mcg::fuzz {

inline std::string_view text_of(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// Every mcg::Error message is one line of printable text (the contract of quote()): a
/// message that breaks it is a finding, reported by aborting as a sanitizer would.
inline void check_message(const mcg::Error& e) {
  for (const char c : std::string_view(e.what())) {
    const auto b = static_cast<unsigned char>(c);
    if (b < 0x20 || b == 0x7f) {
      std::fprintf(stderr, "fuzz: an error message carries byte 0x%02x: %s\n", b, e.what());
      std::abort();
    }
  }
}

/// A finding that is not a crash: a broken round trip or invariant.
[[noreturn]] inline void finding(const char* what) {
  std::fprintf(stderr, "fuzz: %s\n", what);
  std::abort();
}

}  // namespace mcg::fuzz
