// A policy model on one kernel with its data, for the tests that run every kernel.
#pragma once

#include <doctest/doctest.h>

#include <memory>
#include <optional>

#include "runtime/policy/policy_model.hpp"

namespace pbppo::test {

struct ModelAndData {
  explicit ModelAndData(policy::PolicyModel m) : model(std::move(m)) {}
  policy::PolicyModel model;  // does not move: the data refers to it
  std::optional<policy::PolicyData> data;
};

// `spec` on kernel `k` and its data, both required to build.
inline std::unique_ptr<ModelAndData> OnKernel(const policy::PolicySpec& spec, policy::Kernel k) {
  auto model = policy::PolicyModel::FromSpec(spec, {.kernel = k});
  REQUIRE_MESSAGE(model.ok(), model.error().message);
  auto run = std::make_unique<ModelAndData>(std::move(*model));
  auto data = policy::MakePolicyData(run->model);
  REQUIRE_MESSAGE(data.ok(), data.error().message);
  run->data.emplace(std::move(*data));
  return run;
}

}  // namespace pbppo::test
