// Test support: the message of the InputError a piece of code throws, for asserting that error
// messages name the file, line or key (util/error.h's promise to users).
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "moslam/util/error.h"

namespace moslam::testing {

// Runs `f` and returns the InputError's message; fails the test (and returns "") when `f` throws
// nothing.
template <typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected InputError";
  return {};
}

}  // namespace moslam::testing
