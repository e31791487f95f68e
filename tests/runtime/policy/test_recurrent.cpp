// Recurrent layers (LSTM, GRU): every kernel against the float64 reference over long sequences,
// the state's life (reset, non-finite input, save and restore), and their blob records.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "runtime/core/crc32.hpp"
#include "runtime/core/random.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/policy_model.hpp"
#include "runtime/policy/reference.hpp"
#include "runtime/policy/self_test.hpp"
#include "tests/support/golden_check.hpp"
#include "tests/support/policy_on_kernel.hpp"

using namespace pbppo::policy;

namespace {

struct Net {
  const char* name;
  std::vector<std::uint32_t> widths;
  std::vector<LayerKind> kinds;  // per layer, dense when missing
  bool linear_before_reset = false;
  ActionHead head = ActionHead::kLinear;
};

PolicySpec Build(const Net& net, std::uint64_t seed) {
  PolicySpec s = MakeRandomSpec(net.widths, Activation::kElu, seed);
  for (std::size_t i = 0; i < net.kinds.size(); ++i) {
    if (net.kinds[i] == LayerKind::kDense) continue;
    const PolicySpec r =
        MakeRandomRecurrentSpec(net.widths, Activation::kElu, i, net.kinds[i], net.linear_before_reset, seed + 17 * i);
    s.layers[i] = r.layers[i];
  }
  s.action_head = net.head;
  return s;
}

const Net kNets[] = {
    {"lstm-64 (rsl_rl's shape)", {48, 64, 128, 12}, {LayerKind::kLstm}},
    {"lstm-256", {48, 256, 128, 64, 12}, {LayerKind::kLstm}},
    {"gru-64", {48, 64, 64, 12}, {LayerKind::kGru}},
    {"gru-64 linear_before_reset", {48, 64, 64, 12}, {LayerKind::kGru}, true},
    {"stacked lstm", {20, 32, 32, 16, 4}, {LayerKind::kLstm, LayerKind::kLstm}},
    {"dense then gru", {9, 24, 17, 5}, {LayerKind::kDense, LayerKind::kGru}, true, ActionHead::kTanh},
    {"odd lstm", {7, 5, 3}, {LayerKind::kLstm}, false, ActionHead::kTanh},
    {"lstm-1", {3, 1, 2}, {LayerKind::kLstm}},
    {"gru-17", {5, 17, 2}, {LayerKind::kGru}},
};

using pbppo::test::Deviation;

}  // namespace

TEST_CASE("recurrent policies: every kernel within the bound over 300-step sequences and under 1e-5") {
  for (const Net& net : kNets) {
    const PolicySpec spec = Build(net, 31);
    REQUIRE(ValidateSpec(spec).ok());
    const GoldenVectors g = MakeGoldenVectors(spec, 300, 8);
    for (Kernel k : AvailableKernels()) {
      const std::string name = std::string(net.name) + " on " + ToString(k);
      CAPTURE(name);
      auto model = PolicyModel::FromSpec(spec, {.kernel = k});
      REQUIRE_MESSAGE(model.ok(), model.error().message);
      CHECK(model->recurrent());
      const Deviation d = pbppo::test::CheckGolden(*model, g);
      MESSAGE(name << ": max |error| " << d.worst_abs << ", " << d.worst_ratio << " of the bound");
      CHECK(d.worst_abs < 1e-5);
      CHECK(SelfTest(*model, g).ok());
    }
  }
}

TEST_CASE("the state is carried: the same observation twice gives two actions, a reset repeats the first") {
  const PolicySpec spec = Build(kNets[0], 5);
  for (Kernel k : AvailableKernels()) {
    const auto run = pbppo::test::OnKernel(spec, k);
    PolicyData& data = *run->data;
    CHECK(data.state().size() == run->model.state_size());
    CHECK(run->model.state_size() == 2 * 64);  // h and c, each padded to 16
    std::fill(data.observation().begin(), data.observation().end(), 0.3f);
    REQUIRE(Forward(run->model, data) == ForwardStatus::kOk);
    const std::vector<float> first(data.action().begin(), data.action().end());
    REQUIRE(Forward(run->model, data) == ForwardStatus::kOk);
    const std::vector<float> second(data.action().begin(), data.action().end());
    CHECK(first != second);
    data.ResetState();
    for (float v : data.state()) CHECK(v == 0.0f);
    REQUIRE(Forward(run->model, data) == ForwardStatus::kOk);
    CHECK(std::vector<float>(data.action().begin(), data.action().end()) == first);
  }
}

TEST_CASE("a non-finite observation leaves the state as it was") {
  const PolicySpec spec = Build(kNets[2], 6);
  for (Kernel k : AvailableKernels()) {
    const auto run = pbppo::test::OnKernel(spec, k);
    PolicyData& data = *run->data;
    std::fill(data.observation().begin(), data.observation().end(), -0.2f);
    REQUIRE(Forward(run->model, data) == ForwardStatus::kOk);
    const std::vector<float> before(data.state().begin(), data.state().end());
    data.observation()[3] = std::numeric_limits<float>::quiet_NaN();
    CHECK(Forward(run->model, data) == ForwardStatus::kNonFiniteObservation);
    CHECK(std::vector<float>(data.state().begin(), data.state().end()) == before);
  }
}

TEST_CASE("a saved state restored into other data continues the sequence bit for bit") {
  const PolicySpec spec = Build(kNets[4], 7);
  for (Kernel k : AvailableKernels()) {
    const auto a = pbppo::test::OnKernel(spec, k);
    const auto b = pbppo::test::OnKernel(spec, k);
    pbppo::Rng rng(3);
    std::vector<std::vector<float>> obs(40, std::vector<float>(spec.input_size));
    for (auto& o : obs)
      for (float& v : o) v = static_cast<float>(rng.Normal());
    for (int t = 0; t < 20; ++t) {
      std::copy(obs[t].begin(), obs[t].end(), a->data->observation().begin());
      REQUIRE(Forward(a->model, *a->data) == ForwardStatus::kOk);
    }
    std::copy(a->data->state().begin(), a->data->state().end(), b->data->state().begin());
    for (int t = 20; t < 40; ++t) {
      for (auto* r : {a.get(), b.get()}) {
        std::copy(obs[t].begin(), obs[t].end(), r->data->observation().begin());
        REQUIRE(Forward(r->model, *r->data) == ForwardStatus::kOk);
      }
      CHECK(std::memcmp(a->data->action().data(), b->data->action().data(), spec.output_size * sizeof(float)) == 0);
    }
  }
}

TEST_CASE("a feed-forward policy has no state and is written as format v1, a recurrent one as v2") {
  const PolicySpec ff = MakeRandomSpec({4, 8, 2}, Activation::kTanh, 1);
  auto m = PolicyModel::FromSpec(ff);
  REQUIRE(m.ok());
  CHECK_FALSE(m->recurrent());
  auto d = MakePolicyData(*m);
  REQUIRE(d.ok());
  CHECK(d->state().empty());
  auto ff_bytes = EncodeBlob(ff);
  REQUIRE(ff_bytes.ok());
  CHECK((*ff_bytes)[8] == 1);

  for (const Net& net : kNets) {
    CAPTURE(net.name);
    const PolicySpec spec = Build(net, 9);
    auto bytes = EncodeBlob(spec);
    REQUIRE_MESSAGE(bytes.ok(), bytes.error().message);
    CHECK((*bytes)[8] == 2);
    auto back = DecodeBlob(*bytes);
    REQUIRE_MESSAGE(back.ok(), back.error().message);
    REQUIRE(back->layers.size() == spec.layers.size());
    for (std::size_t i = 0; i < spec.layers.size(); ++i) {
      const Layer &x = spec.layers[i], &y = back->layers[i];
      CHECK(x.kind == y.kind);
      CHECK(x.linear_before_reset == y.linear_before_reset);
      CHECK(x.weight == y.weight);
      CHECK(x.bias == y.bias);
      CHECK(x.recurrent_weight == y.recurrent_weight);
      CHECK(x.recurrent_bias == y.recurrent_bias);
    }
    CHECK(back->ParameterCount() == spec.ParameterCount());
    auto again = EncodeBlob(*back);
    REQUIRE(again.ok());
    CHECK(*again == *bytes);
  }
}

namespace {

// The blob of `spec` with the u32 at `offset` set to `value` and the CRC recomputed.
std::vector<std::uint8_t> Patched(const PolicySpec& spec, std::size_t offset, std::uint32_t value) {
  auto bytes = EncodeBlob(spec);
  REQUIRE(bytes.ok());
  std::memcpy(bytes->data() + offset, &value, 4);
  const std::uint32_t crc = pbppo::Crc32(bytes->data(), bytes->size() - 4);
  std::memcpy(bytes->data() + bytes->size() - 4, &crc, 4);
  return *bytes;
}

std::string DecodeError(const std::vector<std::uint8_t>& b) {
  auto r = DecodeBlob(b);
  REQUIRE_FALSE(r.ok());
  return r.error().message;
}

}  // namespace

TEST_CASE("recurrent layer records: every wrong field refused, naming the layer and the value") {
  const PolicySpec spec = Build(kNets[3], 4);  // GRU, linear_before_reset, then two dense layers
  const std::size_t rec0 = kBlobHeaderBytes, rec1 = rec0 + kLayerRecordBytesV2;
  CHECK(DecodeError(Patched(spec, rec0 + 16, 7)) == "policy blob: layer 0: kind 7 unknown (0 dense, 1 lstm, 2 gru)");
  CHECK(DecodeError(Patched(spec, rec0 + 20, 2)) == "policy blob: layer 0: flags 2 not defined for a gru layer");
  CHECK(DecodeError(Patched(spec, rec0 + 8, 1)) ==
        "policy blob: layer 0: a gru layer has activation tanh (only identity: its output is h)");
  CHECK(DecodeError(Patched(spec, rec1 + 20, 1)) == "policy blob: layer 1: flags 1 on a dense layer");
  // Making the GRU an LSTM changes the sizes the table implies: refused before any weight is read.
  CHECK(DecodeError(Patched(spec, rec0 + 16, 1)).find("layer 0: flags 1 not defined for a lstm layer") !=
        std::string::npos);
  // v2 without a recurrent layer, v3, a v1 header over v2 records.
  CHECK(DecodeError(Patched(spec, rec0 + 16, 0)) == "policy blob: layer 0: flags 1 on a dense layer");
  CHECK(DecodeError(Patched(spec, 8, 3)) == "policy blob: format_version 3 unsupported (this loader reads 1..2)");
  CHECK(DecodeError(Patched(spec, 8, 1)) ==
        "policy blob: layer 1: input width 2 does not match the previous width 64");  // read as 16-byte records

  PolicySpec no_flag = spec;
  no_flag.layers[0].linear_before_reset = false;
  CHECK(DecodeError(Patched(no_flag, rec0 + 16, 0)) ==
        "policy blob: format_version 2 without a recurrent layer (such a policy is written as v1)");

  // The writer's own checks.
  auto refused = [](const PolicySpec& s) {
    auto st = ValidateSpec(s);
    REQUIRE_FALSE(st.ok());
    return st.error().message;
  };
  PolicySpec last = MakeRandomRecurrentSpec({4, 6, 3}, Activation::kElu, 0, LayerKind::kLstm, false, 1);
  last.layers.pop_back();
  last.layers[0].out = 3;
  last.output_size = 3;
  CHECK(refused(last).find("layer 0: a lstm layer cannot be the last") != std::string::npos);
  PolicySpec short_r = spec;
  short_r.layers[0].recurrent_weight.pop_back();
  CHECK(refused(short_r) == "policy blob: layer 0 recurrent_weight: has 12287 values, expected 12288");
  PolicySpec nan_rb = spec;
  nan_rb.layers[0].recurrent_bias[5] = std::numeric_limits<float>::quiet_NaN();
  CHECK(refused(nan_rb) == "policy blob: layer 0 recurrent_bias[5]: non-finite value nan");
  PolicySpec act = spec;
  act.layers[0].activation = Activation::kElu;
  CHECK(refused(act) == "policy blob: layer 0: a gru layer has activation elu (only identity: its output is h)");
  PolicySpec lbr = MakeRandomRecurrentSpec({4, 6, 3}, Activation::kElu, 0, LayerKind::kLstm, false, 1);
  lbr.layers[0].linear_before_reset = true;
  CHECK(refused(lbr) == "policy blob: layer 0: flags 1 not defined for a lstm layer");
  PolicySpec dense_r = MakeRandomSpec({4, 6, 3}, Activation::kElu, 1);
  dense_r.layers[0].recurrent_bias.assign(6, 0.0f);
  CHECK(refused(dense_r) == "policy blob: layer 0 recurrent_bias: has 6 values, expected 0");
}

TEST_CASE("every single-byte change of a recurrent blob is refused") {
  const PolicySpec spec = Build(kNets[7], 2);  // lstm-1: a small blob
  auto bytes = EncodeBlob(spec);
  REQUIRE(bytes.ok());
  int refused = 0;
  for (std::size_t i = 0; i < bytes->size(); ++i) {
    std::vector<std::uint8_t> b = *bytes;
    b[i] ^= 0x5A;
    refused += !DecodeBlob(b).ok();
  }
  CHECK(refused == static_cast<int>(bytes->size()));
}
