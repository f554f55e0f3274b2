// The message of the mcg::Error a callable throws: the one helper the unit tests use to
// assert exact error text.
#pragma once

#include <string>

#include "common/error.hpp"

namespace mcg::test {

/// What `f()` throws as mcg::Error, or "(no error)" when it returns normally. Any other
/// exception propagates (and fails the test).
template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace mcg::test
