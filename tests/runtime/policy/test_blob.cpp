#include <doctest/doctest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "runtime/core/crc32.hpp"
#include "runtime/policy/blob.hpp"
#include "runtime/policy/reference.hpp"
#include "tests/support/test_paths.hpp"

using namespace pbppo::policy;

namespace {
PolicySpec Small() {
  return MakeRandomSpec({5, 7, 3}, Activation::kTanh, 11);
}

std::string ErrorOf(const PolicySpec& s, const BlobLimits& limits = {}) {
  auto bytes = EncodeBlob(s);
  if (!bytes) return bytes.error().message;
  auto back = DecodeBlob(*bytes, limits);
  return back ? std::string() : back.error().message;
}
}  // namespace

TEST_CASE("a blob round-trips every field") {
  PolicySpec s = MakeRandomSpec({48, 64, 32, 12}, Activation::kElu, 5);
  s.action_head = ActionHead::kTanh;
  s.io_layout_hash = 0x0123456789abcdefull;
  s.provenance = {"pbppo 0.1.0", "abc1234", "auv-nav/hard", "pbppo arms=0.05:0.4:6", 17, 2000000, -123.5};
  auto bytes = EncodeBlob(s);
  REQUIRE(bytes.ok());
  auto back = DecodeBlob(*bytes);
  REQUIRE_MESSAGE(back.ok(), back.error().message);
  const PolicySpec& t = *back;
  CHECK(t.input_size == 48);
  CHECK(t.output_size == 12);
  REQUIRE(t.layers.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(t.layers[i].in == s.layers[i].in);
    CHECK(t.layers[i].out == s.layers[i].out);
    CHECK(t.layers[i].activation == s.layers[i].activation);
    CHECK(t.layers[i].weight == s.layers[i].weight);
    CHECK(t.layers[i].bias == s.layers[i].bias);
  }
  CHECK(t.obs_mean == s.obs_mean);
  CHECK(t.obs_inv_std == s.obs_inv_std);
  CHECK(t.obs_clip == s.obs_clip);
  CHECK(t.action_head == ActionHead::kTanh);
  CHECK(t.action_scale == s.action_scale);
  CHECK(t.action_offset == s.action_offset);
  CHECK(t.action_low == s.action_low);
  CHECK(t.action_high == s.action_high);
  CHECK(t.io_layout_hash == s.io_layout_hash);
  CHECK(t.observation_names == s.observation_names);
  CHECK(t.action_names == s.action_names);
  CHECK(t.provenance.trainer_version == "pbppo 0.1.0");
  CHECK(t.provenance.git_revision == "abc1234");
  CHECK(t.provenance.environment == "auv-nav/hard");
  CHECK(t.provenance.clip_schedule == "pbppo arms=0.05:0.4:6");
  CHECK(t.provenance.seed == 17);
  CHECK(t.provenance.env_steps == 2000000);
  CHECK(t.provenance.final_return == -123.5);
  // Re-encoding the decoded spec gives the same bytes.
  auto again = EncodeBlob(t);
  REQUIRE(again.ok());
  CHECK(*again == *bytes);
}

TEST_CASE("the stored crc32 covers everything before it") {
  auto bytes = EncodeBlob(Small());
  REQUIRE(bytes.ok());
  std::uint32_t stored = 0;
  std::memcpy(&stored, bytes->data() + bytes->size() - 4, 4);
  CHECK(stored == pbppo::Crc32(bytes->data(), bytes->size() - 4));
}

TEST_CASE("capacity limits are enforced with messages naming field and value") {
  PolicySpec s = MakeRandomSpec({4, 8, 900, 2}, Activation::kRelu, 1);
  BlobLimits tight;
  tight.max_width = 512;
  CHECK(ErrorOf(s, tight) == "policy blob: layer 1: width 900 exceeds limit 512");
  tight = {};
  tight.max_input = 3;
  CHECK(ErrorOf(s, tight) == "policy blob: input_size 4 outside 1..3");
  tight = {};
  tight.max_layers = 2;
  CHECK(ErrorOf(s, tight) == "policy blob: layer_count 3 outside 1..2");
  tight = {};
  tight.max_parameters = 100;
  CHECK(ErrorOf(s, tight).find("parameter count") != std::string::npos);
}

TEST_CASE("invalid values are refused by the writer, naming the field") {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  auto expect = [](PolicySpec s, const std::string& msg) {
    auto r = EncodeBlob(s);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == msg);
  };
  PolicySpec s = Small();
  s.layers[1].weight[4] = nan;
  expect(s, "policy blob: layer 1 weight[4]: non-finite value nan");
  s = Small();
  s.layers[0].bias[2] = -inf;
  expect(s, "policy blob: layer 0 bias[2]: non-finite value -inf");
  s = Small();
  s.obs_inv_std[3] = 0.0f;
  expect(s, "policy blob: obs_inv_std[3]: 0 is not positive");
  s = Small();
  s.obs_clip = -1.0f;
  expect(s, "policy blob: obs_clip: -1 is not a positive finite number");
  s = Small();
  s.action_low[1] = 2.0f;
  expect(s, "policy blob: action_low[1] 2 is above action_high 1");
  s = Small();
  s.layers[1].in = 6;
  expect(s, "policy blob: layer 1: input width 6 does not match the previous width 7");
  s = Small();
  s.action_names.pop_back();
  expect(s, "policy blob: action_names: has 2 names, expected 3");
  s = Small();
  s.observation_names[0] = "bad name";
  expect(s, "policy blob: observation_names[0]: byte 0x20 is not a printable ASCII name character");
  s = Small();
  s.layers[0].weight.pop_back();
  expect(s, "policy blob: layer 0 weight: has 34 values, expected 35");
}

TEST_CASE("activation names parse back, leaky_relu included") {
  for (Activation a :
       {Activation::kIdentity, Activation::kTanh, Activation::kElu, Activation::kRelu, Activation::kLeakyRelu}) {
    Activation back = Activation::kIdentity;
    REQUIRE(ParseActivation(ToString(a), &back));
    CHECK(back == a);
  }
  CHECK(std::string(ToString(Activation::kLeakyRelu)) == "leaky_relu");
  CHECK(static_cast<std::uint32_t>(Activation::kLeakyRelu) == 4);
  Activation a = Activation::kTanh;
  CHECK_FALSE(ParseActivation("leaky", &a));
  CHECK(a == Activation::kTanh);
}

TEST_CASE("MakeRandomSpec gives hidden leaky_relu layers alpha 0.01 and the output layer none") {
  const PolicySpec s = MakeRandomSpec({6, 9, 8, 3}, Activation::kLeakyRelu, 7);
  REQUIRE(s.layers.size() == 3);
  for (std::size_t i = 0; i < 2; ++i) {
    CHECK(s.layers[i].activation == Activation::kLeakyRelu);
    CHECK(s.layers[i].alpha == 0.01f);
  }
  CHECK(s.layers[2].activation == Activation::kIdentity);
  CHECK(s.layers[2].alpha == 0.0f);
  CHECK(ValidateSpec(s).ok());
  for (const Layer& l : MakeRandomSpec({6, 9, 3}, Activation::kRelu, 7).layers) CHECK(l.alpha == 0.0f);
}

TEST_CASE("a leaky_relu layer's alpha round-trips as float32 bits in the layer record's 4th word") {
  PolicySpec s = MakeRandomSpec({6, 9, 8, 5, 3}, Activation::kLeakyRelu, 7);
  s.layers[0].alpha = 0.37f;
  s.layers[1].alpha = 1.0f;  // both ends of [0, 1] are valid
  s.layers[2].alpha = 0.0f;
  s.layers[3].activation = Activation::kLeakyRelu;  // the output layer may have one too
  s.layers[3].alpha = 0x1.fffffep-1f;
  auto bytes = EncodeBlob(s);
  REQUIRE(bytes.ok());
  for (std::size_t i = 0; i < s.layers.size(); ++i) {
    std::uint32_t rec[4];
    std::memcpy(rec, bytes->data() + kBlobHeaderBytes + i * kLayerRecordBytes, sizeof rec);
    CHECK(rec[2] == 4u);
    CHECK(rec[3] == std::bit_cast<std::uint32_t>(s.layers[i].alpha));
  }
  auto back = DecodeBlob(*bytes);
  REQUIRE_MESSAGE(back.ok(), back.error().message);
  for (std::size_t i = 0; i < s.layers.size(); ++i) {
    CHECK(back->layers[i].activation == Activation::kLeakyRelu);
    CHECK(std::bit_cast<std::uint32_t>(back->layers[i].alpha) == std::bit_cast<std::uint32_t>(s.layers[i].alpha));
    CHECK(back->layers[i].weight == s.layers[i].weight);
  }
  auto again = EncodeBlob(*back);
  REQUIRE(again.ok());
  CHECK(*again == *bytes);

  // Other activations keep the word 0, and decode with alpha 0.
  bytes = EncodeBlob(MakeRandomSpec({5, 7, 3}, Activation::kElu, 2));
  REQUIRE(bytes.ok());
  for (std::size_t i = 0; i < 2; ++i) {
    std::uint32_t word = 1;
    std::memcpy(&word, bytes->data() + kBlobHeaderBytes + i * kLayerRecordBytes + 12, 4);
    CHECK(word == 0u);
  }
  back = DecodeBlob(*bytes);
  REQUIRE(back.ok());
  for (const Layer& l : back->layers) CHECK(std::bit_cast<std::uint32_t>(l.alpha) == 0u);
}

TEST_CASE("the writer refuses a leaky_relu alpha outside [0, 1] and an alpha on any other layer") {
  auto expect = [](PolicySpec s, const std::string& msg) {
    const auto st = ValidateSpec(s);
    REQUIRE_FALSE(st.ok());
    CHECK(st.error().message == msg);
    auto r = EncodeBlob(s);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == msg);
  };
  const PolicySpec leaky = MakeRandomSpec({5, 7, 6, 3}, Activation::kLeakyRelu, 3);
  PolicySpec s = leaky;
  s.layers[1].alpha = 1.5f;
  expect(s, "policy blob: layer 1: leaky_relu alpha 1.5 outside [0, 1]");
  s.layers[1].alpha = -0.25f;
  expect(s, "policy blob: layer 1: leaky_relu alpha -0.25 outside [0, 1]");
  s.layers[1].alpha = std::nextafter(1.0f, 2.0f);
  expect(s, "policy blob: layer 1: leaky_relu alpha 1.00000012 outside [0, 1]");
  s.layers[1].alpha = std::numeric_limits<float>::quiet_NaN();
  expect(s, "policy blob: layer 1: leaky_relu alpha nan outside [0, 1]");
  s.layers[0].alpha = std::numeric_limits<float>::infinity();
  expect(s, "policy blob: layer 0: leaky_relu alpha inf outside [0, 1]");
  s = leaky;
  s.layers[2].alpha = 0.5f;  // the identity output layer
  expect(s, "policy blob: layer 2: alpha 0.5 given for activation identity (only leaky_relu has one)");
  s = Small();
  s.layers[0].alpha = -0.0f;  // not even a negative zero: the word must stay 0
  expect(s, "policy blob: layer 0: alpha -0 given for activation tanh (only leaky_relu has one)");
}

TEST_CASE("files are written atomically and read back, errors name the path") {
  const std::string dir = pbppo::test::ScratchDir("blob_files");
  const std::string path = dir + "/p.blob";
  REQUIRE(WriteBlobFile(path, Small()).ok());
  auto back = ReadBlobFile(path);
  REQUIRE(back.ok());
  CHECK(back->input_size == 5);
  // Nothing but the blob is left in the folder.
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    (void)e;
    ++files;
  }
  CHECK(files == 1);

  // A writer that fails leaves the old file intact.
  PolicySpec bad = Small();
  bad.obs_clip = 0.0f;
  CHECK_FALSE(WriteBlobFile(path, bad).ok());
  CHECK(ReadBlobFile(path).ok());
  CHECK_FALSE(WriteBlobFile(dir + "/missing/p.blob", Small()).ok());

  auto missing = ReadBlobFile(dir + "/nope.blob");
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().message.find(dir + "/nope.blob: cannot open") == 0);

  std::ofstream(dir + "/junk.blob") << "this is not a policy blob, only a text that is longer than a header";
  auto junk = ReadBlobFile(dir + "/junk.blob");
  REQUIRE_FALSE(junk.ok());
  CHECK(junk.error().message ==
        dir + "/junk.blob: policy blob: magic: not a pbppo policy blob (expected \"PBPPOPOL\")");
}

namespace {
// The folder's file names, sorted.
std::vector<std::string> FilesIn(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string Contents(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}
}  // namespace

TEST_CASE("a blob and its golden vectors are written together, or neither changes") {
  const std::string dir = pbppo::test::ScratchDir("policy_files");
  const std::string blob = dir + "/p.blob", golden = dir + "/p.golden";
  const PolicySpec spec = Small();
  REQUIRE(WritePolicyFiles(blob, spec, MakeGoldenVectors(spec, 8, 3)).ok());
  CHECK(FilesIn(dir) == std::vector<std::string>{"p.blob", "p.golden"});
  auto back = ReadBlobFile(blob);
  REQUIRE(back.ok());
  auto rows = ReadGoldenFile(golden);
  REQUIRE(rows.ok());
  CHECK(rows->observations.size() == 8);
  CHECK(rows->expected[5].action == ReferenceForward(*back, rows->observations[5].data()).action);
  const std::string blob_bytes = Contents(blob), golden_bytes = Contents(golden);

  // Refusals before anything is written: the previous pair stays, no temporary is left.
  const PolicySpec other = MakeRandomSpec({6, 7, 3}, Activation::kTanh, 12);
  auto wrong_shape = WritePolicyFiles(blob, spec, MakeGoldenVectors(other, 8, 3));
  REQUIRE_FALSE(wrong_shape.ok());
  CHECK(wrong_shape.error().message ==
        golden + ": golden vectors of 6 observations and 3 actions for a policy of 5 and 3");
  PolicySpec bad = MakeRandomSpec({5, 9, 3}, Activation::kTanh, 13);
  const GoldenVectors bad_rows = MakeGoldenVectors(bad, 8, 3);
  bad.obs_clip = 0.0f;
  CHECK_FALSE(WritePolicyFiles(blob, bad, bad_rows).ok());
  // A folder where the blob goes: its golden file is not replaced either.
  std::filesystem::create_directory(dir + "/q.blob");
  std::ofstream(dir + "/q.golden") << "the previous golden file";
  auto folder = WritePolicyFiles(dir + "/q.blob", spec, MakeGoldenVectors(spec, 8, 3));
  REQUIRE_FALSE(folder.ok());
  CHECK(folder.error().message == dir + "/q.blob: is a folder, not a file");
  CHECK(Contents(dir + "/q.golden") == "the previous golden file");
  auto missing = WritePolicyFiles(dir + "/missing/p.blob", spec, MakeGoldenVectors(spec, 8, 3));
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().message.find(dir + "/missing/p.golden.tmp.") == 0);
  CHECK(missing.error().message.find(": cannot create: ") != std::string::npos);
  CHECK(Contents(blob) == blob_bytes);
  CHECK(Contents(golden) == golden_bytes);
  CHECK(FilesIn(dir) == std::vector<std::string>{"p.blob", "p.golden", "q.blob", "q.golden"});

  // A new pair replaces both.
  const PolicySpec next = MakeRandomSpec({5, 7, 3}, Activation::kTanh, 14);
  REQUIRE(WritePolicyFiles(blob, next, MakeGoldenVectors(next, 4, 9)).ok());
  CHECK(Contents(blob) != blob_bytes);
  CHECK(ReadGoldenFile(golden)->observations.size() == 4);
  CHECK(FilesIn(dir) == std::vector<std::string>{"p.blob", "p.golden", "q.blob", "q.golden"});
}
