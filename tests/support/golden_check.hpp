// A model against golden vectors (runtime/policy/reference.hpp): the rows in order on fresh data
// (a recurrent policy's rows are one sequence), every action within its row's bound.
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>

#include "runtime/policy/policy_model.hpp"
#include "runtime/policy/reference.hpp"

namespace pbppo::test {

struct Deviation {
  double worst_ratio = 0.0;  // max |runtime - reference| / bound
  double worst_abs = 0.0;
};

inline Deviation CheckGolden(const policy::PolicyModel& model, const policy::GoldenVectors& g) {
  auto data = policy::MakePolicyData(model);
  REQUIRE(data.ok());
  Deviation dev;
  for (std::size_t r = 0; r < g.observations.size(); ++r) {
    std::copy(g.observations[r].begin(), g.observations[r].end(), data->observation().begin());
    REQUIRE(policy::Forward(model, *data) == policy::ForwardStatus::kOk);
    for (std::size_t j = 0; j < g.output_size; ++j) {
      const double got = data->action()[j];
      const double want = g.expected[r].action[j];
      const double bound = g.expected[r].error_bound[j];
      const double err = std::fabs(got - want);
      dev.worst_abs = std::max(dev.worst_abs, err);
      dev.worst_ratio = std::max(dev.worst_ratio, err / bound);
      if (!(err <= bound)) {
        FAIL_CHECK("kernel " << policy::ToString(model.kernel()) << " row " << r << " action " << j << ": " << got
                             << " vs reference " << want << ", error " << err << " > bound " << bound);
        return dev;
      }
    }
  }
  return dev;
}

}  // namespace pbppo::test
