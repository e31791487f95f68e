// The message a parser refused its input with, for tests that list bad inputs and the errors that
// name them: `CHECK(RefusalOf(ParseCanMap(text, "t.yaml")) == "t.yaml: motors[1] ...")`.
#pragma once

#include <string>

namespace pbppo::test {

// The error's message, or "" when the input was accepted (which then fails the caller's CHECK
// against the expected message, showing both).
template <typename R>
std::string RefusalOf(const R& result) {
  return result.ok() ? std::string() : result.error().message;
}

}  // namespace pbppo::test
