// The self-test at arming (runtime/policy/self_test.hpp): every shipped blob and test blob passes
// its golden vectors on every kernel this CPU has; a changed reference output, a shape that does
// not fit and a missing golden file are refused, naming the row, the shape or the file.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>

#include "runtime/policy/policy_model.hpp"
#include "runtime/policy/reference.hpp"
#include "runtime/policy/self_test.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo::policy;
using pbppo::test::ScratchDir;
using pbppo::test::SourcePath;

TEST_CASE("self-test: the shipped and test blobs pass their golden vectors on every kernel") {
  for (const char* rel : {"policies/frozen/auv_nav/auv_nav.blob", "policies/frozen/quadruped_walk/flat.blob",
                          "policies/frozen/quadruped_walk/mixed.blob", "tests/data/blobs/p1.blob",
                          "tests/data/blobs/p2.blob", "tests/data/blobs/p3.blob"}) {
    for (Kernel k : AvailableKernels()) {
      const std::string blob_name = rel;
      CAPTURE(blob_name);
      const std::string kernel_name = ToString(k);
      CAPTURE(kernel_name);
      LoadOptions o;
      o.kernel = k;
      auto model = PolicyModel::FromFile(SourcePath(rel), o);
      REQUIRE(model);
      const auto st = SelfTest(*model, SourcePath(rel));
      CHECK_MESSAGE(st, (st ? std::string() : st.error().message));
    }
  }
}

TEST_CASE("self-test: a mismatch names the row and action, a wrong shape and a missing file are refused") {
  const std::string blob = SourcePath("tests/data/blobs/p1.blob");
  auto model = PolicyModel::FromFile(blob);
  REQUIRE(model);
  auto golden = ReadGoldenFile(GoldenPathFor(blob));
  REQUIRE(golden);
  REQUIRE(golden->observations.size() > 3);

  GoldenVectors changed = *golden;
  changed.expected[3].action[0] += 0.5f;
  auto st = SelfTest(*model, changed);
  REQUIRE_FALSE(st);
  CHECK(st.error().message.find("golden vectors: row 3 action 0:") == 0);
  CHECK(st.error().message.find(std::string("kernel ") + ToString(model->kernel())) != std::string::npos);

  GoldenVectors shape = *golden;
  ++shape.input_size;
  st = SelfTest(*model, shape);
  REQUIRE_FALSE(st);
  CHECK(st.error().message.find("golden vectors: shape") == 0);

  GoldenVectors empty = *golden;
  empty.observations.clear();
  empty.expected.clear();
  st = SelfTest(*model, empty);
  REQUIRE_FALSE(st);
  CHECK(st.error().message.find("no rows") != std::string::npos);

  const std::string dir = ScratchDir("self_test_missing");
  const std::string copy = dir + "/lonely.blob";
  std::filesystem::copy_file(blob, copy, std::filesystem::copy_options::overwrite_existing);
  std::filesystem::remove(dir + "/lonely.golden");
  st = SelfTest(*model, copy);
  REQUIRE_FALSE(st);
  CHECK(st.error().message.find("self-test: ") == 0);
  CHECK(st.error().message.find("lonely.golden") != std::string::npos);
}
