// The --kernel option of every program that runs a policy (pbppo eval, pbppo replay,
// pbppo-controller): one name list, one description. Header-only; include it only where CLI11 is
// used (the runtime libraries do not).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "runtime/policy/policy_model.hpp"

namespace pbppo::policy {

// Adds --kernel NAME (a name KernelFromName reads) to `app`, stored in `kernel` ("auto" unless given).
inline CLI::Option* AddKernelOption(CLI::App& app, std::string& kernel) {
  return app
      .add_option("--kernel", kernel,
                  "Forward kernel: auto (AVX-512 where the CPU has it, NEON on aarch64), portable (the same results "
                  "on every machine that runs this build), avx512 or neon")
      ->check(CLI::IsMember({"auto", "portable", "avx512", "neon"}));
}

// The kernel of a name AddKernelOption accepted.
inline Kernel KernelOption(const std::string& kernel) {
  return KernelFromName(kernel).value_or(Kernel::kAuto);
}

// What a program that arms with a policy says of it: "on the neon kernel, its golden vectors passed".
inline std::string KernelNote(const PolicyModel& model, bool self_test_skipped) {
  return std::string("on the ") + ToString(model.kernel()) + " kernel" +
         (self_test_skipped ? " (self-test skipped)" : ", its golden vectors passed");
}

}  // namespace pbppo::policy
