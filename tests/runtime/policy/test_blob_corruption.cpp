// Exhaustive robustness of the blob loader: every single-byte corruption, every truncation,
// and header fields corrupted with a recomputed CRC (so the CRC is not the only guard).
#include <doctest/doctest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "runtime/core/crc32.hpp"
#include "runtime/policy/blob.hpp"

using namespace pbppo::policy;

namespace {

std::vector<std::uint8_t> SmallBlob() {
  PolicySpec s = MakeRandomSpec({3, 4, 2}, Activation::kTanh, 9);
  s.provenance.git_revision = "0123abc";
  auto b = EncodeBlob(s);
  REQUIRE(b.ok());
  return *b;
}

void Recrc(std::vector<std::uint8_t>& b) {
  const std::uint32_t c = pbppo::Crc32(b.data(), b.size() - 4);
  std::memcpy(b.data() + b.size() - 4, &c, 4);
}

template <typename T>
void Put(std::vector<std::uint8_t>& b, std::size_t off, T v) {
  std::memcpy(b.data() + off, &v, sizeof v);
}

std::string Refused(std::vector<std::uint8_t> b) {
  auto r = DecodeBlob(b);
  return r.ok() ? std::string() : r.error().message;
}

}  // namespace

TEST_CASE("every single-byte corruption is rejected") {
  const auto good = SmallBlob();
  REQUIRE(DecodeBlob(good).ok());
  std::size_t tried = 0, rejected = 0;
  for (std::size_t pos = 0; pos < good.size(); ++pos) {
    for (int v = 0; v < 256; ++v) {
      if (v == good[pos]) continue;
      auto b = good;
      b[pos] = static_cast<std::uint8_t>(v);
      ++tried;
      auto r = DecodeBlob(b);
      if (!r.ok()) {
        ++rejected;
        CHECK_FALSE(r.error().message.empty());
      }
    }
  }
  CHECK(tried == good.size() * 255);
  CHECK(rejected == tried);
}

TEST_CASE("every truncation and any padding is rejected") {
  const auto good = SmallBlob();
  for (std::size_t n = 0; n < good.size(); ++n) {
    std::vector<std::uint8_t> b(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(n));
    auto r = DecodeBlob(b);
    CHECK_FALSE(r.ok());
  }
  auto padded = good;
  padded.push_back(0);
  CHECK(Refused(padded).find("file_bytes") != std::string::npos);
  CHECK(Refused({}) == "policy blob: truncated: 0 bytes, a blob has at least 52");
}

TEST_CASE("structural header fields corrupted under a valid CRC are rejected, naming the field") {
  const auto good = SmallBlob();
  // Every value of every byte of the structural fields, CRC recomputed: never accepted.
  const std::size_t layer0 = kBlobHeaderBytes, layer1 = kBlobHeaderBytes + kLayerRecordBytes;
  std::vector<std::size_t> structural;
  for (std::size_t off = 0; off < 40; ++off) structural.push_back(off);  // magic .. action_head
  for (std::size_t off = layer0; off < layer1 + kLayerRecordBytes; ++off) {
    if ((off - layer0) % kLayerRecordBytes >= 8 && (off - layer0) % kLayerRecordBytes < 12)
      continue;  // activation: 0..4 are all valid (4, leaky_relu, with alpha 0 in the next word)
    structural.push_back(off);
  }
  std::size_t accepted = 0;
  for (std::size_t off : structural) {
    if (off >= 36 && off < 40) continue;  // action_head: 0 and 1 are both valid; checked below
    for (int v = 0; v < 256; ++v) {
      if (v == good[off]) continue;
      auto b = good;
      b[off] = static_cast<std::uint8_t>(v);
      Recrc(b);
      if (DecodeBlob(b).ok()) ++accepted;
    }
  }
  CHECK(accepted == 0);

  auto with = [&](std::size_t off, std::uint32_t v) {
    auto b = good;
    Put(b, off, v);
    Recrc(b);
    return Refused(b);
  };
  CHECK(with(kOffVersion, 3) == "policy blob: format_version 3 unsupported (this loader reads 1..2)");
  CHECK(with(kOffVersion, 0) == "policy blob: format_version 0 unsupported (this loader reads 1..2)");
  // v1 records read as v2 ones (24 bytes): the 5th word, the next record's input width, is no kind.
  CHECK(with(kOffVersion, 2) == "policy blob: layer 0: kind 4 unknown (0 dense, 1 lstm, 2 gru)");
  CHECK(with(kOffHeaderBytes, 64) == "policy blob: header_bytes 64, format v1 has 48");
  CHECK(with(kOffInputSize, 0) == "policy blob: input_size 0 outside 1..1024");
  CHECK(with(kOffInputSize, 100000) == "policy blob: input_size 100000 outside 1..1024");
  CHECK(with(kOffInputSize, 4) == "policy blob: layer 0: input width 3 does not match the previous width 4");
  CHECK(with(kOffOutputSize, 3) == "policy blob: layer 1: width 2 of the last layer does not match output_size 3");
  CHECK(with(kOffLayerCount, 0) == "policy blob: layer_count 0 outside 1..16");
  CHECK(with(kOffLayerCount, 0xFFFFFFFFu) == "policy blob: layer_count 4294967295 outside 1..16");
  // A third layer record is read from the normaliser's bytes: refused on its widths.
  CHECK(with(kOffLayerCount, 3).rfind("policy blob: layer 2: input width", 0) == 0);
  CHECK(with(kOffActionHead, 7) == "policy blob: action_head 7 unknown (0..1)");
  CHECK(with(layer0 + 4, 900) == "policy blob: layer 1: input width 4 does not match the previous width 900");
  CHECK(with(layer0 + 4, 5000) == "policy blob: layer 0: width 5000 exceeds limit 2048");
  CHECK(with(layer0 + 8, 5) == "policy blob: layer 0: activation 5 unknown (0..4)");
  CHECK(with(layer0 + 12, 1) == "policy blob: layer 0: reserved field 1 is not 0");

  auto b = good;
  Put<std::uint64_t>(b, kOffFileBytes, 1ull << 40);
  Recrc(b);
  CHECK(Refused(b) == "policy blob: file_bytes 1099511627776 exceeds limit 134217728");
}

TEST_CASE("a leaky_relu alpha outside [0, 1], or a non-zero 4th word on another layer, is rejected under a valid CRC") {
  PolicySpec spec = MakeRandomSpec({3, 4, 2}, Activation::kLeakyRelu, 9);
  REQUIRE(spec.layers[0].activation == Activation::kLeakyRelu);
  REQUIRE(spec.layers[1].activation == Activation::kIdentity);
  auto encoded = EncodeBlob(spec);
  REQUIRE(encoded.ok());
  const std::vector<std::uint8_t> good = *encoded;
  const std::size_t layer0 = kBlobHeaderBytes, layer1 = kBlobHeaderBytes + kLayerRecordBytes;
  auto with = [&](std::size_t off, std::uint32_t v) {
    auto b = good;
    Put(b, off, v);
    Recrc(b);
    return b;
  };
  auto alpha = [&](float a) { return with(layer0 + 12, std::bit_cast<std::uint32_t>(a)); };

  CHECK(Refused(alpha(1.5f)) == "policy blob: layer 0: leaky_relu alpha 1.5 outside [0, 1]");
  CHECK(Refused(alpha(-0.125f)) == "policy blob: layer 0: leaky_relu alpha -0.125 outside [0, 1]");
  CHECK(Refused(alpha(std::numeric_limits<float>::quiet_NaN())) ==
        "policy blob: layer 0: leaky_relu alpha nan outside [0, 1]");
  CHECK(Refused(alpha(-std::numeric_limits<float>::infinity())) ==
        "policy blob: layer 0: leaky_relu alpha -inf outside [0, 1]");
  CHECK(Refused(with(layer0 + 12, 0xFFFFFFFFu)) == "policy blob: layer 0: leaky_relu alpha -nan outside [0, 1]");
  for (float a : {0.0f, 0.25f, 1.0f, 0x1p-149f}) {
    auto back = DecodeBlob(alpha(a));
    REQUIRE_MESSAGE(back.ok(), back.error().message);
    CHECK(back->layers[0].alpha == a);
  }

  // The identity output layer's word, and the leaky layer's once it becomes tanh: reserved, 0.
  CHECK(Refused(with(layer1 + 12, std::bit_cast<std::uint32_t>(0.5f))) ==
        "policy blob: layer 1: reserved field 1056964608 is not 0");
  CHECK(Refused(with(layer0 + 8, 1)) == "policy blob: layer 0: reserved field 1008981770 is not 0");
  // The other way round: a tanh layer becomes leaky_relu with alpha 0, which is valid.
  auto b = SmallBlob();
  Put<std::uint32_t>(b, layer0 + 8, 4);
  Recrc(b);
  auto back = DecodeBlob(b);
  REQUIRE_MESSAGE(back.ok(), back.error().message);
  CHECK(back->layers[0].activation == Activation::kLeakyRelu);
  CHECK(back->layers[0].alpha == 0.0f);
}

TEST_CASE("non-finite parameters and bad names under a valid CRC are rejected") {
  const auto good = SmallBlob();
  const std::size_t params = kBlobHeaderBytes + 2 * kLayerRecordBytes;
  // obs_mean[0] is the first float after the layer table.
  auto b = good;
  Put(b, params, std::numeric_limits<float>::quiet_NaN());
  Recrc(b);
  CHECK(Refused(b) == "policy blob: obs_mean[0]: non-finite value nan");
  // layer 0 weight[1]: after mean[3], inv_std[3], clip.
  b = good;
  Put(b, params + 4 * (3 + 3 + 1 + 1), std::numeric_limits<float>::infinity());
  Recrc(b);
  CHECK(Refused(b) == "policy blob: layer 0 weight[1]: non-finite value inf");
  // The first observation name starts after all floats: its length prefix, then "obs0".
  const std::size_t floats = 3 + 3 + 1 + (3 * 4 + 4) + (4 * 2 + 2) + 4 * 2;
  const std::size_t name = params + 4 * floats;
  std::uint16_t len = 0;
  std::memcpy(&len, good.data() + name, 2);
  REQUIRE(len == 4);
  b = good;
  b[name + 2] = 0x07;
  Recrc(b);
  CHECK(Refused(b) == "policy blob: observation_names[0]: byte 0x07 is not a printable ASCII name character");
  b = good;
  Put<std::uint16_t>(b, name, 0xFFFF);
  Recrc(b);
  CHECK(Refused(b) == "policy blob: observation_names[0]: length 65535 exceeds limit 64");
  b = good;
  Put<std::uint16_t>(b, name, 60);
  Recrc(b);
  CHECK_FALSE(Refused(b).empty());
}
