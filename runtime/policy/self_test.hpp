// The self-test at arming: a policy's golden vectors (the writer's float64 reference outputs and
// their error bounds, "x.golden" beside "x.blob") run through the engine the controller will use.
// A controller refuses to arm on a mismatch, naming the row. Set-up time only (allocates).
#pragma once

#include <string>

#include "runtime/core/result.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/policy/reference.hpp"

namespace pbppo::policy {

// Every row within its float32 error bound, else "golden vectors: row 3 action 1: 0.25 vs
// reference 0.5 (error 0.25 > bound 1e-06), kernel avx512". Shapes must match the model.
Status SelfTest(const PolicyModel& model, const GoldenVectors& golden);
// The golden file beside the blob (GoldenPathFor), read and run; errors name the file.
Status SelfTest(const PolicyModel& model, const std::string& blob_path);

}  // namespace pbppo::policy
