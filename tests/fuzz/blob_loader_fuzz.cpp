// libFuzzer target: arbitrary bytes into the blob loader. A blob that loads must run: the
// forward pass on a fixed observation gives actions inside [low, high] (or NaN when flagged).
// Each input is tried as is and, so that mutations reach the parser behind the checksum, with
// its file_bytes and CRC repaired.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "runtime/core/crc32.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/policy_model.hpp"

namespace {

void TryLoad(const std::uint8_t* data, std::size_t size) {
  using namespace pbppo::policy;
  BlobLimits limits;
  limits.max_parameters = 1u << 20;  // keep each input fast
  auto model = PolicyModel::FromBlob({data, size}, {.limits = limits});
  if (!model) {
    if (model.error().message.empty()) std::abort();
    return;
  }
  auto pd = MakePolicyData(*model);
  if (!pd) std::abort();
  for (std::size_t i = 0; i < pd->observation().size(); ++i) pd->observation()[i] = static_cast<float>(i % 7) - 3.0f;
  const ForwardStatus st = Forward(*model, *pd);
  const PolicySpec& d = model->description();
  for (std::size_t j = 0; j < pd->action().size(); ++j) {
    const float a = pd->action()[j];
    if (std::isnan(a)) {
      if (st != ForwardStatus::kNonFiniteAction) std::abort();
    } else if (!(a >= d.action_low[j] && a <= d.action_high[j])) {
      std::abort();
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  TryLoad(data, size);
  if (size >= pbppo::policy::kBlobHeaderBytes + 4) {
    std::vector<std::uint8_t> fixed(data, data + size);
    const std::uint64_t n = size;
    std::memcpy(fixed.data() + pbppo::policy::kOffFileBytes, &n, sizeof n);
    const std::uint32_t crc = pbppo::Crc32(fixed.data(), size - 4);
    std::memcpy(fixed.data() + size - 4, &crc, sizeof crc);
    TryLoad(fixed.data(), size);
  }
  return 0;
}
