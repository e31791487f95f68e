#include "runtime/policy/self_test.hpp"

#include <cmath>
#include <cstdio>

namespace pbppo::policy {

Status SelfTest(const PolicyModel& model, const GoldenVectors& g) {
  auto fail = [&](const std::string& what) {
    return MakeError(ErrorCode::kMismatch,
                     std::string("golden vectors: ") + what + ", kernel " + ToString(model.kernel()));
  };
  if (g.input_size != model.input_size() || g.output_size != model.output_size())
    return fail("shape " + std::to_string(g.input_size) + " -> " + std::to_string(g.output_size) + ", the policy's " +
                std::to_string(model.input_size()) + " -> " + std::to_string(model.output_size()));
  if (g.observations.empty()) return fail("no rows");
  auto data = MakePolicyData(model);
  if (!data) return std::move(data).error();
  for (std::size_t r = 0; r < g.observations.size(); ++r) {
    std::copy(g.observations[r].begin(), g.observations[r].end(), data->observation().begin());
    const ForwardStatus st = Forward(model, *data);
    if (st != ForwardStatus::kOk) return fail("row " + std::to_string(r) + ": Forward returned " + ToString(st));
    for (std::size_t j = 0; j < g.output_size; ++j) {
      const auto got = static_cast<double>(data->action()[j]);
      const double want = g.expected[r].action[j];
      const double bound = g.expected[r].error_bound[j];
      const double err = std::fabs(got - want);
      if (!(err <= bound)) {
        char b[200];
        std::snprintf(b, sizeof b, "row %zu action %zu: %.9g vs reference %.9g (error %.3g > bound %.3g)", r, j, got,
                      want, err, bound);
        return fail(b);
      }
    }
  }
  return {};
}

Status SelfTest(const PolicyModel& model, const std::string& blob_path) {
  const std::string path = GoldenPathFor(blob_path);
  auto g = ReadGoldenFile(path);
  if (!g) return MakeError(g.error().code, "self-test: " + g.error().message);
  if (auto st = SelfTest(model, *g); !st) return MakeError(st.error().code, path + ": " + st.error().message);
  return {};
}

}  // namespace pbppo::policy
