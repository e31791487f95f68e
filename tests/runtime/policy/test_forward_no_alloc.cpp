// After set-up, Forward() makes no heap allocation: 100,000 calls per kernel and network (2,000
// under an emulator, tens of times slower), every malloc and operator new counted, with Eigen's own
// allocation check armed as well; recurrent networks among them (their state carried, and reset).
#include <doctest/doctest.h>

#include "runtime/core/alloc_probe.hpp"
#include "runtime/core/random.hpp"
#include "runtime/policy/policy_model.hpp"
#include "tests/support/policy_on_kernel.hpp"

using namespace pbppo::policy;

TEST_CASE("the allocation counter sees allocations") {
  REQUIRE(pbppo::AllocationCountingActive());
  pbppo::AllocationScope scope;
  // The pointers escape through an asm barrier, so the compiler cannot elide the pairs.
  auto* p = new int[64];
  asm volatile("" : : "r"(p) : "memory");
  delete[] p;
  void* q = std::malloc(32);
  asm volatile("" : : "r"(q) : "memory");
  std::free(q);
  CHECK(scope.count() >= 2);
}

#ifdef PBPPO_EMULATED
constexpr int kCalls = 2000;
#else
constexpr int kCalls = 100000;
#endif

TEST_CASE("100,000 forward calls allocate nothing") {
  struct Net {
    std::vector<std::uint32_t> widths;
    Activation act;
    LayerKind first = LayerKind::kDense;  // the first layer's kind (a recurrent one carries state)
  };
  for (const Net& net :
       {Net{{48, 512, 256, 128, 12}, Activation::kElu}, Net{{24, 64, 64, 2}, Activation::kElu},
        Net{{24, 64, 64, 2}, Activation::kLeakyRelu}, Net{{48, 64, 64, 12}, Activation::kElu, LayerKind::kLstm},
        Net{{48, 64, 64, 12}, Activation::kElu, LayerKind::kGru}}) {
    const PolicySpec spec = net.first == LayerKind::kDense
                                ? MakeRandomSpec(net.widths, net.act, 2)
                                : MakeRandomRecurrentSpec(net.widths, net.act, 0, net.first, false, 2);
    for (Kernel k : AvailableKernels()) {
      const std::string kernel_name = ToString(k);
      CAPTURE(kernel_name);
      const auto run = pbppo::test::OnKernel(spec, k);
      const PolicyModel* model = &run->model;
      PolicyData* data = &*run->data;
      pbppo::Rng rng(4);
      std::uint64_t allocations = 0;
      int bad = 0;
      SetEigenMallocAllowed(false);
      {
        pbppo::AllocationScope scope;
        for (int call = 0; call < kCalls; ++call) {
          auto obs = data->observation();
          obs[static_cast<std::size_t>(call) % obs.size()] = static_cast<float>(rng.Normal());
          bad += Forward(*model, *data) != ForwardStatus::kOk;
          if (call % 1000 == 999) data->ResetState();
        }
        allocations = scope.count();
      }
      SetEigenMallocAllowed(true);
      CHECK(bad == 0);
      CHECK(allocations == 0);
      CHECK(data->forward_calls == kCalls);
    }
  }
}
