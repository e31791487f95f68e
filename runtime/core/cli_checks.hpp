// CLI11 checks the project's programs share (pbppo, pbppo-hil, pbppo-controller, ...), so that a
// bad value is refused with the same words everywhere: "--seed: '-4' is not a non-negative
// integer". Header-only; include it only where CLI11 is used (the runtime libraries do not).
#pragma once

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <string>

namespace pbppo::cli_checks {

// A non-negative integer in decimal that fits 64 bits. (CLI11 converts "-4" into an unsigned
// option as 2^64 - 4, and 2^64 as 2^64 - 1.)
inline CLI::Validator NonNegativeInteger() {
  return CLI::Validator(
      [](const std::string& v) {
        bool digits = !v.empty();
        for (char c : v) digits = digits && c >= '0' && c <= '9';
        errno = 0;
        if (digits) std::strtoull(v.c_str(), nullptr, 10);
        return digits && errno != ERANGE ? std::string() : "'" + v + "' is not an integer in [0, 2^64)";
      },
      "N >= 0");
}

// A finite number of seconds above zero.
inline CLI::Validator PositiveSeconds() {
  return CLI::Validator(
      [](const std::string& v) {
        char* end = nullptr;
        const double d = std::strtod(v.c_str(), &end);
        const bool ok = end != v.c_str() && *end == '\0' && std::isfinite(d) && d > 0;
        return ok ? std::string() : "'" + v + "' is not a positive number of seconds";
      },
      "SECONDS > 0");
}

}  // namespace pbppo::cli_checks
