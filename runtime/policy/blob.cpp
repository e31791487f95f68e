#include "runtime/policy/blob.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string_view>

#include "runtime/core/crc32.hpp"
#include "runtime/core/write_all.hpp"

namespace pbppo::policy {
namespace {

std::string Str(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
std::string Str(const char* fmt, ...) {
  char buf[512];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  return buf;
}

Error Fail(ErrorCode code, const std::string& what) {
  return MakeError(code, "policy blob: " + what);
}

// ---------------------------------------------------------------- validation

Status CheckFiniteArray(const std::vector<float>& v, std::size_t expected, const char* field) {
  if (v.size() != expected) {
    return Fail(ErrorCode::kMismatch, Str("%s: has %zu values, expected %zu", field, v.size(), expected));
  }
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      return Fail(ErrorCode::kInvalidValue, Str("%s[%zu]: non-finite value %g", field, i, static_cast<double>(v[i])));
    }
  }
  return {};
}

Status CheckName(const std::string& s, std::uint32_t max_bytes, const char* field, std::size_t index) {
  if (s.empty()) return Fail(ErrorCode::kInvalidValue, Str("%s[%zu]: empty name", field, index));
  if (s.size() > max_bytes) {
    return Fail(ErrorCode::kLimit, Str("%s[%zu]: name length %zu exceeds limit %u", field, index, s.size(), max_bytes));
  }
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x21 || c > 0x7E) {
      return Fail(ErrorCode::kInvalidValue,
                  Str("%s[%zu]: byte 0x%02x is not a printable ASCII name character", field, index, c));
    }
  }
  return {};
}

Status CheckText(const std::string& s, std::uint32_t max_bytes, const char* field) {
  if (s.size() > max_bytes) {
    return Fail(ErrorCode::kLimit, Str("%s: length %zu exceeds limit %u", field, s.size(), max_bytes));
  }
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c > 0x7E) {
      return Fail(ErrorCode::kInvalidValue, Str("%s: byte 0x%02x is not printable ASCII", field, c));
    }
  }
  return {};
}

// Structural checks that only need sizes: used by the loader before it allocates.
Status CheckShape(std::uint32_t input, std::uint32_t output, std::uint32_t layer_count, const BlobLimits& limits) {
  if (input == 0 || input > limits.max_input) {
    return Fail(ErrorCode::kLimit, Str("input_size %u outside 1..%u", input, limits.max_input));
  }
  if (output == 0 || output > limits.max_output) {
    return Fail(ErrorCode::kLimit, Str("output_size %u outside 1..%u", output, limits.max_output));
  }
  if (layer_count == 0 || layer_count > limits.max_layers) {
    return Fail(ErrorCode::kLimit, Str("layer_count %u outside 1..%u", layer_count, limits.max_layers));
  }
  return {};
}

Status CheckLayerShape(std::size_t index, std::uint32_t in, std::uint32_t out, std::uint32_t act,
                       std::uint32_t expected_in, bool last, std::uint32_t output, const BlobLimits& limits) {
  // Widths stay below 2^24 whatever the limits say, so that parameter counts cannot overflow.
  const std::uint32_t max_width = std::min(limits.max_width, 1u << 24);
  if (in == 0 || in > max_width) {
    return Fail(ErrorCode::kLimit, Str("layer %zu: input width %u outside 1..%u", index, in, max_width));
  }
  if (out == 0 || out > max_width) {
    return Fail(ErrorCode::kLimit, Str("layer %zu: width %u exceeds limit %u", index, out, max_width));
  }
  if (in != expected_in) {
    return Fail(ErrorCode::kMismatch,
                Str("layer %zu: input width %u does not match the previous width %u", index, in, expected_in));
  }
  if (last && out != output) {
    return Fail(ErrorCode::kMismatch,
                Str("layer %zu: width %u of the last layer does not match output_size %u", index, out, output));
  }
  if (act > static_cast<std::uint32_t>(Activation::kLeakyRelu)) {
    return Fail(ErrorCode::kInvalidValue, Str("layer %zu: activation %u unknown (0..4)", index, act));
  }
  return {};
}

// A layer's kind and flags: a known kind; a recurrent layer is not the last (the action comes from
// a dense layer), has no activation of its own, and only a GRU has the linear_before_reset flag.
Status CheckLayerKind(std::size_t index, std::uint32_t kind, std::uint32_t flags, std::uint32_t act, bool last) {
  if (kind > static_cast<std::uint32_t>(LayerKind::kGru)) {
    return Fail(ErrorCode::kInvalidValue, Str("layer %zu: kind %u unknown (0 dense, 1 lstm, 2 gru)", index, kind));
  }
  const auto k = static_cast<LayerKind>(kind);
  if (k == LayerKind::kDense) {
    if (flags != 0) return Fail(ErrorCode::kInvalidValue, Str("layer %zu: flags %u on a dense layer", index, flags));
    return {};
  }
  if (last) {
    return Fail(
        ErrorCode::kInvalidValue,
        Str("layer %zu: a %s layer cannot be the last (the action comes from a dense layer)", index, ToString(k)));
  }
  if (act != static_cast<std::uint32_t>(Activation::kIdentity)) {
    return Fail(ErrorCode::kInvalidValue,
                Str("layer %zu: a %s layer has activation %s (only identity: its output is h)", index, ToString(k),
                    ToString(static_cast<Activation>(act))));
  }
  const std::uint32_t allowed = k == LayerKind::kGru ? kLayerFlagLinearBeforeReset : 0u;
  if ((flags & ~allowed) != 0) {
    return Fail(ErrorCode::kInvalidValue,
                Str("layer %zu: flags %u not defined for a %s layer", index, flags, ToString(k)));
  }
  return {};
}

// The leaky_relu slope of a layer whose activation is known: finite and in [0, 1] (the error
// bound of the golden vectors needs every activation 1-Lipschitz). Other activations have none.
Status CheckLayerAlpha(std::size_t index, Activation act, float alpha) {
  if (act == Activation::kLeakyRelu) {
    if (!(alpha >= 0.0f && alpha <= 1.0f)) {  // NaN fails too
      return Fail(ErrorCode::kInvalidValue,
                  Str("layer %zu: leaky_relu alpha %.9g outside [0, 1]", index, static_cast<double>(alpha)));
    }
    return {};
  }
  if (std::bit_cast<std::uint32_t>(alpha) != 0) {
    return Fail(ErrorCode::kInvalidValue, Str("layer %zu: alpha %.9g given for activation %s (only leaky_relu has one)",
                                              index, static_cast<double>(alpha), ToString(act)));
  }
  return {};
}

// ---------------------------------------------------------------- byte writer / reader

class ByteWriter {
 public:
  void U16(std::uint16_t v) { Raw(&v, 2); }
  void U32(std::uint32_t v) { Raw(&v, 4); }
  void U64(std::uint64_t v) { Raw(&v, 8); }
  void F64(double v) { Raw(&v, 8); }
  void Floats(const std::vector<float>& v) { Raw(v.data(), v.size() * sizeof(float)); }
  void Text(const std::string& s) {
    U16(static_cast<std::uint16_t>(s.size()));
    Raw(s.data(), s.size());
  }
  void Raw(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    bytes.insert(bytes.end(), b, b + n);
  }
  std::vector<std::uint8_t> bytes;
};
static_assert(std::endian::native == std::endian::little,
              "the blob format is little-endian; add byte swaps for this host");

class ByteReader {
 public:
  ByteReader(std::span<const std::uint8_t> b, std::size_t end) : b_(b), end_(end) {}
  std::size_t pos() const { return pos_; }
  std::size_t left() const { return end_ - pos_; }

  bool Raw(void* out, std::size_t n) {
    if (n > left()) return false;
    std::memcpy(out, b_.data() + pos_, n);
    pos_ += n;
    return true;
  }
  bool U16(std::uint16_t* v) { return Raw(v, 2); }
  bool U32(std::uint32_t* v) { return Raw(v, 4); }
  bool U64(std::uint64_t* v) { return Raw(v, 8); }
  bool F64(double* v) { return Raw(v, 8); }
  bool Floats(std::vector<float>* v, std::size_t n) {
    if (n > left() / sizeof(float)) return false;
    v->resize(n);
    return Raw(v->data(), n * sizeof(float));
  }
  // A length-prefixed string of at most max_bytes.
  Status Text(std::string* s, std::uint32_t max_bytes, const std::string& field) {
    std::uint16_t n = 0;
    if (!U16(&n)) return Fail(ErrorCode::kFormat, field + ": truncated");
    if (n > max_bytes)
      return Fail(ErrorCode::kLimit, Str("%s: length %u exceeds limit %u", field.c_str(), n, max_bytes));
    if (n > left()) return Fail(ErrorCode::kFormat, field + ": truncated");
    s->assign(reinterpret_cast<const char*>(b_.data() + pos_), n);
    pos_ += n;
    return {};
  }

 private:
  std::span<const std::uint8_t> b_;
  std::size_t end_;
  std::size_t pos_ = 0;
};

template <typename T>
T Load(std::span<const std::uint8_t> b, std::size_t off) {
  T v;
  std::memcpy(&v, b.data() + off, sizeof v);
  return v;
}

}  // namespace

// ---------------------------------------------------------------- public

Status ValidateSpec(const PolicySpec& s, const BlobLimits& limits) {
  const auto layer_count = static_cast<std::uint32_t>(std::min<std::size_t>(s.layers.size(), 0xFFFFFFFFu));
  if (auto st = CheckShape(s.input_size, s.output_size, layer_count, limits); !st) return st;
  std::uint32_t prev = s.input_size;
  std::uint64_t params = 0;
  for (std::size_t i = 0; i < s.layers.size(); ++i) {
    const Layer& l = s.layers[i];
    const bool last = i + 1 == s.layers.size();
    if (auto st = CheckLayerShape(i, l.in, l.out, static_cast<std::uint32_t>(l.activation), prev, last, s.output_size,
                                  limits);
        !st) {
      return st;
    }
    if (auto st = CheckLayerKind(i, static_cast<std::uint32_t>(l.kind),
                                 l.linear_before_reset ? kLayerFlagLinearBeforeReset : 0u,
                                 static_cast<std::uint32_t>(l.activation), last);
        !st) {
      return st;
    }
    if (auto st = CheckLayerAlpha(i, l.activation, l.alpha); !st) return st;
    params += l.ParameterCount();
    if (params > limits.max_parameters) {
      return Fail(ErrorCode::kLimit,
                  Str("layer %zu: parameter count reaches %llu, over limit %llu", i,
                      static_cast<unsigned long long>(params), static_cast<unsigned long long>(limits.max_parameters)));
    }
    const std::size_t rows = static_cast<std::size_t>(l.gates()) * l.out;
    const bool rec = l.kind != LayerKind::kDense;
    const std::string w = Str("layer %zu weight", i), b = Str("layer %zu bias", i);
    const std::string rw = Str("layer %zu recurrent_weight", i), rb = Str("layer %zu recurrent_bias", i);
    if (auto st = CheckFiniteArray(l.weight, rows * l.in, w.c_str()); !st) return st;
    if (auto st = CheckFiniteArray(l.bias, rows, b.c_str()); !st) return st;
    if (auto st = CheckFiniteArray(l.recurrent_weight, rec ? rows * l.out : 0, rw.c_str()); !st) return st;
    if (auto st = CheckFiniteArray(l.recurrent_bias, rec ? rows : 0, rb.c_str()); !st) return st;
    prev = l.out;
  }
  if (auto st = CheckFiniteArray(s.obs_mean, s.input_size, "obs_mean"); !st) return st;
  if (auto st = CheckFiniteArray(s.obs_inv_std, s.input_size, "obs_inv_std"); !st) return st;
  for (std::size_t i = 0; i < s.obs_inv_std.size(); ++i) {
    if (!(s.obs_inv_std[i] > 0.0f)) {
      return Fail(ErrorCode::kInvalidValue,
                  Str("obs_inv_std[%zu]: %g is not positive", i, static_cast<double>(s.obs_inv_std[i])));
    }
  }
  if (!(std::isfinite(s.obs_clip) && s.obs_clip > 0.0f)) {
    return Fail(ErrorCode::kInvalidValue,
                Str("obs_clip: %g is not a positive finite number", static_cast<double>(s.obs_clip)));
  }
  if (static_cast<std::uint32_t>(s.action_head) > static_cast<std::uint32_t>(ActionHead::kTanh)) {
    return Fail(ErrorCode::kInvalidValue, Str("action_head %u unknown (0..1)", static_cast<unsigned>(s.action_head)));
  }
  if (auto st = CheckFiniteArray(s.action_scale, s.output_size, "action_scale"); !st) return st;
  if (auto st = CheckFiniteArray(s.action_offset, s.output_size, "action_offset"); !st) return st;
  if (auto st = CheckFiniteArray(s.action_low, s.output_size, "action_low"); !st) return st;
  if (auto st = CheckFiniteArray(s.action_high, s.output_size, "action_high"); !st) return st;
  for (std::size_t i = 0; i < s.output_size; ++i) {
    if (!(s.action_low[i] <= s.action_high[i])) {
      return Fail(ErrorCode::kInvalidValue,
                  Str("action_low[%zu] %g is above action_high %g", i, static_cast<double>(s.action_low[i]),
                      static_cast<double>(s.action_high[i])));
    }
  }
  if (s.observation_names.size() != s.input_size) {
    return Fail(ErrorCode::kMismatch,
                Str("observation_names: has %zu names, expected %u", s.observation_names.size(), s.input_size));
  }
  if (s.action_names.size() != s.output_size) {
    return Fail(ErrorCode::kMismatch,
                Str("action_names: has %zu names, expected %u", s.action_names.size(), s.output_size));
  }
  for (std::size_t i = 0; i < s.observation_names.size(); ++i) {
    if (auto st = CheckName(s.observation_names[i], limits.max_name_bytes, "observation_names", i); !st) return st;
  }
  for (std::size_t i = 0; i < s.action_names.size(); ++i) {
    if (auto st = CheckName(s.action_names[i], limits.max_name_bytes, "action_names", i); !st) return st;
  }
  const Provenance& p = s.provenance;
  if (auto st = CheckText(p.trainer_version, limits.max_text_bytes, "provenance.trainer_version"); !st) return st;
  if (auto st = CheckText(p.git_revision, limits.max_text_bytes, "provenance.git_revision"); !st) return st;
  if (auto st = CheckText(p.environment, limits.max_text_bytes, "provenance.environment"); !st) return st;
  if (auto st = CheckText(p.clip_schedule, limits.max_text_bytes, "provenance.clip_schedule"); !st) return st;
  if (std::isnan(p.final_return)) return Fail(ErrorCode::kInvalidValue, "provenance.final_return: NaN");
  return {};
}

Result<std::vector<std::uint8_t>> EncodeBlob(const PolicySpec& s) {
  if (auto st = ValidateSpec(s); !st) return st.error();
  ByteWriter w;
  const bool v2 = s.Recurrent();
  w.Raw(kBlobMagic, sizeof kBlobMagic);
  w.U32(v2 ? kBlobFormatVersion : kBlobFeedForwardVersion);
  w.U32(kBlobHeaderBytes);
  w.U64(0);  // file_bytes, patched below
  w.U32(s.input_size);
  w.U32(s.output_size);
  w.U32(static_cast<std::uint32_t>(s.layers.size()));
  w.U32(static_cast<std::uint32_t>(s.action_head));
  w.U64(s.io_layout_hash);
  for (const Layer& l : s.layers) {
    w.U32(l.in);
    w.U32(l.out);
    w.U32(static_cast<std::uint32_t>(l.activation));
    w.U32(std::bit_cast<std::uint32_t>(l.alpha));  // leaky_relu's slope; 0 for the others (validated)
    if (v2) {
      w.U32(static_cast<std::uint32_t>(l.kind));
      w.U32(l.linear_before_reset ? kLayerFlagLinearBeforeReset : 0u);
    }
  }
  w.Floats(s.obs_mean);
  w.Floats(s.obs_inv_std);
  w.Raw(&s.obs_clip, sizeof(float));
  for (const Layer& l : s.layers) {
    w.Floats(l.weight);
    w.Floats(l.bias);
    w.Floats(l.recurrent_weight);  // empty for a dense layer
    w.Floats(l.recurrent_bias);
  }
  w.Floats(s.action_scale);
  w.Floats(s.action_offset);
  w.Floats(s.action_low);
  w.Floats(s.action_high);
  for (const auto& n : s.observation_names) w.Text(n);
  for (const auto& n : s.action_names) w.Text(n);
  w.Text(s.provenance.trainer_version);
  w.Text(s.provenance.git_revision);
  w.Text(s.provenance.environment);
  w.Text(s.provenance.clip_schedule);
  w.U64(s.provenance.seed);
  w.U64(s.provenance.env_steps);
  w.F64(s.provenance.final_return);
  const std::uint64_t total = w.bytes.size() + 4;
  std::memcpy(w.bytes.data() + kOffFileBytes, &total, sizeof total);
  w.U32(Crc32(w.bytes.data(), w.bytes.size()));
  return std::move(w.bytes);
}

namespace {

// The blob's frame: size, magic, version, header size, declared size, CRC.
Status CheckFrame(std::span<const std::uint8_t> b, const BlobLimits& limits) {
  constexpr std::size_t kMin = kBlobHeaderBytes + 4;
  if (b.size() < kMin) {
    return Fail(ErrorCode::kFormat, Str("truncated: %zu bytes, a blob has at least %zu", b.size(), kMin));
  }
  if (std::memcmp(b.data(), kBlobMagic, sizeof kBlobMagic) != 0) {
    return Fail(ErrorCode::kFormat, "magic: not a pbppo policy blob (expected \"PBPPOPOL\")");
  }
  const auto version = Load<std::uint32_t>(b, kOffVersion);
  if (version < kBlobFeedForwardVersion || version > kBlobFormatVersion) {
    return Fail(ErrorCode::kFormat, Str("format_version %u unsupported (this loader reads %u..%u)", version,
                                        kBlobFeedForwardVersion, kBlobFormatVersion));
  }
  const auto header_bytes = Load<std::uint32_t>(b, kOffHeaderBytes);
  if (header_bytes != kBlobHeaderBytes) {
    return Fail(ErrorCode::kFormat, Str("header_bytes %u, format v%u has %u", header_bytes, version, kBlobHeaderBytes));
  }
  const auto file_bytes = Load<std::uint64_t>(b, kOffFileBytes);
  if (file_bytes > limits.max_file_bytes) {
    return Fail(ErrorCode::kLimit,
                Str("file_bytes %llu exceeds limit %llu", static_cast<unsigned long long>(file_bytes),
                    static_cast<unsigned long long>(limits.max_file_bytes)));
  }
  if (file_bytes != b.size()) {
    return Fail(ErrorCode::kFormat, Str("file_bytes %llu does not match the %zu bytes given (truncated or padded)",
                                        static_cast<unsigned long long>(file_bytes), b.size()));
  }
  const std::size_t body = b.size() - 4;
  const auto stored_crc = Load<std::uint32_t>(b, body);
  const std::uint32_t crc = Crc32(b.data(), body);
  if (crc != stored_crc) {
    return Fail(ErrorCode::kFormat,
                Str("crc32 0x%08x does not match the content (0x%08x): the blob is corrupted", stored_crc, crc));
  }
  return {};
}

// A layer record: in, out, activation, alpha bits, kind, flags (v1 records end after alpha: dense).
using LayerRecords = std::vector<std::array<std::uint32_t, 6>>;

// The layer table, checked completely, and the exact byte count it implies, before anything is
// allocated for the weights.
Status ReadLayerTable(ByteReader& r, const PolicySpec& s, std::uint32_t version, std::uint32_t layer_count,
                      const BlobLimits& limits, LayerRecords* records) {
  const std::uint32_t record_bytes = version >= 2 ? kLayerRecordBytesV2 : kLayerRecordBytes;
  if (r.left() / record_bytes < layer_count) return Fail(ErrorCode::kFormat, "layer table: truncated");
  records->assign(layer_count, {0, 0, 0, 0, 0, 0});
  std::uint32_t prev = s.input_size;
  std::uint64_t params = 0;
  bool recurrent = false;
  for (std::uint32_t i = 0; i < layer_count; ++i) {
    (void)r.Raw((*records)[i].data(), record_bytes);
    const auto& rec = (*records)[i];
    const bool last = i + 1 == layer_count;
    if (auto st = CheckLayerShape(i, rec[0], rec[1], rec[2], prev, last, s.output_size, limits); !st) {
      return st.error();
    }
    if (auto st = CheckLayerKind(i, rec[4], rec[5], rec[2], last); !st) return st.error();
    // The 4th word: leaky_relu's alpha (float32 bits), reserved and 0 for every other activation.
    if (rec[2] == static_cast<std::uint32_t>(Activation::kLeakyRelu)) {
      if (auto st = CheckLayerAlpha(i, Activation::kLeakyRelu, std::bit_cast<float>(rec[3])); !st) return st.error();
    } else if (rec[3] != 0) {
      return Fail(ErrorCode::kFormat, Str("layer %u: reserved field %u is not 0", i, rec[3]));
    }
    Layer shape;
    shape.kind = static_cast<LayerKind>(rec[4]);
    shape.in = rec[0];
    shape.out = rec[1];
    recurrent = recurrent || shape.kind != LayerKind::kDense;
    params += shape.ParameterCount();  // widths below 2^24 (CheckLayerShape): no overflow
    prev = rec[1];
    if (params > limits.max_parameters) break;
  }
  if (version >= 2 && !recurrent) {
    return Fail(ErrorCode::kFormat, "format_version 2 without a recurrent layer (such a policy is written as v1)");
  }
  if (params > limits.max_parameters) {
    return Fail(ErrorCode::kLimit,
                Str("parameter count %llu exceeds limit %llu", static_cast<unsigned long long>(params),
                    static_cast<unsigned long long>(limits.max_parameters)));
  }
  // Floats that must follow: normaliser, weights, action map; then at least the string lengths.
  const std::uint64_t floats = 2ull * s.input_size + 1 + params + 4ull * s.output_size;
  const std::uint64_t min_rest = floats * 4 + 2ull * (s.input_size + s.output_size + 4) + 24;
  if (min_rest > r.left()) {
    return Fail(ErrorCode::kFormat, Str("sizes in the header need at least %llu more bytes, the blob has %zu",
                                        static_cast<unsigned long long>(min_rest), r.left()));
  }
  return {};
}

// The normaliser, the layers' weights, the action map, the names and the provenance.
Status ReadBody(ByteReader& r, const LayerRecords& records, const BlobLimits& limits, PolicySpec* out) {
  PolicySpec& s = *out;
  (void)r.Floats(&s.obs_mean, s.input_size);
  (void)r.Floats(&s.obs_inv_std, s.input_size);
  (void)r.Raw(&s.obs_clip, sizeof(float));
  s.layers.resize(records.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    Layer& l = s.layers[i];
    l.in = records[i][0];
    l.out = records[i][1];
    l.activation = static_cast<Activation>(records[i][2]);
    l.alpha = std::bit_cast<float>(records[i][3]);
    l.kind = static_cast<LayerKind>(records[i][4]);
    l.linear_before_reset = (records[i][5] & kLayerFlagLinearBeforeReset) != 0;
    const std::size_t rows = static_cast<std::size_t>(l.gates()) * l.out;
    (void)r.Floats(&l.weight, rows * l.in);
    (void)r.Floats(&l.bias, rows);
    if (l.kind != LayerKind::kDense) {
      (void)r.Floats(&l.recurrent_weight, rows * l.out);
      (void)r.Floats(&l.recurrent_bias, rows);
    }
  }
  (void)r.Floats(&s.action_scale, s.output_size);
  (void)r.Floats(&s.action_offset, s.output_size);
  (void)r.Floats(&s.action_low, s.output_size);
  (void)r.Floats(&s.action_high, s.output_size);
  s.observation_names.resize(s.input_size);
  for (std::uint32_t i = 0; i < s.input_size; ++i) {
    if (auto st = r.Text(&s.observation_names[i], limits.max_name_bytes, Str("observation_names[%u]", i)); !st)
      return st.error();
  }
  s.action_names.resize(s.output_size);
  for (std::uint32_t i = 0; i < s.output_size; ++i) {
    if (auto st = r.Text(&s.action_names[i], limits.max_name_bytes, Str("action_names[%u]", i)); !st) return st.error();
  }
  Provenance& p = s.provenance;
  if (auto st = r.Text(&p.trainer_version, limits.max_text_bytes, "provenance.trainer_version"); !st) return st.error();
  if (auto st = r.Text(&p.git_revision, limits.max_text_bytes, "provenance.git_revision"); !st) return st.error();
  if (auto st = r.Text(&p.environment, limits.max_text_bytes, "provenance.environment"); !st) return st.error();
  if (auto st = r.Text(&p.clip_schedule, limits.max_text_bytes, "provenance.clip_schedule"); !st) return st.error();
  if (!r.U64(&p.seed) || !r.U64(&p.env_steps) || !r.F64(&p.final_return)) {
    return Fail(ErrorCode::kFormat, "provenance: truncated");
  }
  if (r.left() != 0) return Fail(ErrorCode::kFormat, Str("%zu unexpected bytes before the crc32", r.left()));
  return {};
}

}  // namespace

Result<PolicySpec> DecodeBlob(std::span<const std::uint8_t> b, const BlobLimits& limits) {
  if (auto st = CheckFrame(b, limits); !st) return st.error();
  PolicySpec s;
  s.input_size = Load<std::uint32_t>(b, kOffInputSize);
  s.output_size = Load<std::uint32_t>(b, kOffOutputSize);
  const auto version = Load<std::uint32_t>(b, kOffVersion);  // checked by CheckFrame
  const auto layer_count = Load<std::uint32_t>(b, kOffLayerCount);
  const auto head = Load<std::uint32_t>(b, kOffActionHead);
  s.io_layout_hash = Load<std::uint64_t>(b, kOffIoLayoutHash);
  if (auto st = CheckShape(s.input_size, s.output_size, layer_count, limits); !st) return st.error();
  if (head > static_cast<std::uint32_t>(ActionHead::kTanh)) {
    return Fail(ErrorCode::kInvalidValue, Str("action_head %u unknown (0..1)", head));
  }
  s.action_head = static_cast<ActionHead>(head);
  ByteReader r(b, b.size() - 4);
  std::uint8_t skip[kBlobHeaderBytes];
  (void)r.Raw(skip, kBlobHeaderBytes);
  LayerRecords records;
  if (auto st = ReadLayerTable(r, s, version, layer_count, limits, &records); !st) return st.error();
  if (auto st = ReadBody(r, records, limits, &s); !st) return st.error();
  if (auto st = ValidateSpec(s, limits); !st) return st.error();
  return s;
}

std::string PathBeside(const std::string& blob_path, const std::string& extension) {
  const auto dot = blob_path.rfind('.');
  const auto slash = blob_path.rfind('/');
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash))
    return blob_path.substr(0, dot) + extension;
  return blob_path + extension;
}

Result<std::vector<std::uint8_t>> ReadFileBytes(const std::string& path, std::uint64_t max_bytes) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) return MakeError(ErrorCode::kIo, path + ": cannot open: " + std::strerror(errno));
  const std::streamoff size = f.tellg();
  if (size < 0) return MakeError(ErrorCode::kIo, path + ": cannot read its size");
  if (static_cast<std::uint64_t>(size) > max_bytes) {
    return MakeError(ErrorCode::kLimit, Str("%s: %lld bytes exceeds limit %llu", path.c_str(),
                                            static_cast<long long>(size), static_cast<unsigned long long>(max_bytes)));
  }
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  f.seekg(0);
  if (size > 0 && !f.read(reinterpret_cast<char*>(bytes.data()), size))
    return MakeError(ErrorCode::kIo, path + ": read failed");
  return bytes;
}

Result<PolicySpec> ReadBlobFile(const std::string& path, const BlobLimits& limits) {
  auto bytes = ReadFileBytes(path, limits.max_file_bytes);
  if (!bytes) return std::move(bytes).error();
  auto r = DecodeBlob(*bytes, limits);
  if (!r) return MakeError(r.error().code, path + ": " + r.error().message);
  return r;
}

namespace {

// `bytes` in a temporary file beside `path`, flushed: its name, or an error and nothing left behind.
Result<std::string> WriteTemporary(const std::string& path, std::span<const std::uint8_t> bytes) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return MakeError(ErrorCode::kIo, tmp + ": cannot create: " + std::strerror(errno));
  if (int e = 0; WriteAll(fd, bytes.data(), bytes.size(), &e) != bytes.size()) {
    ::close(fd);
    ::unlink(tmp.c_str());
    return MakeError(ErrorCode::kIo, tmp + ": write failed: " + std::strerror(e));
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    return MakeError(ErrorCode::kIo, tmp + ": flush failed: " + std::strerror(e));
  }
  return tmp;
}

}  // namespace

Status WriteFileAtomic(const std::string& path, std::span<const std::uint8_t> bytes) {
  const FileBytes file{path, bytes};
  return WriteFilesAtomic(std::span(&file, 1));
}

Status WriteFilesAtomic(std::span<const FileBytes> files) {
  // A folder in a file's place would fail its rename after the others: refused before anything.
  for (const FileBytes& f : files) {
    struct stat st{};
    if (::stat(f.path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
      return MakeError(ErrorCode::kIo, f.path + ": is a folder, not a file");
  }
  std::vector<std::string> tmps;
  auto remove_temporaries = [&tmps](std::size_t from) {
    for (std::size_t i = from; i < tmps.size(); ++i) ::unlink(tmps[i].c_str());
  };
  for (const FileBytes& f : files) {
    auto tmp = WriteTemporary(f.path, f.bytes);
    if (!tmp) {
      remove_temporaries(0);
      return std::move(tmp).error();
    }
    tmps.push_back(std::move(*tmp));
  }
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (::rename(tmps[i].c_str(), files[i].path.c_str()) != 0) {
      const int e = errno;
      remove_temporaries(i);
      std::string replaced;
      for (std::size_t k = 0; k < i; ++k) replaced += (k > 0 ? ", " : "") + files[k].path;
      return MakeError(ErrorCode::kIo, files[i].path + ": rename failed: " + std::strerror(e) +
                                           (replaced.empty() ? "" : " (already replaced: " + replaced + ")"));
    }
  }
  return {};
}

Status WriteBlobFile(const std::string& path, const PolicySpec& spec) {
  auto bytes = EncodeBlob(spec);
  if (!bytes) return bytes.error();
  return WriteFileAtomic(path, *bytes);
}

}  // namespace pbppo::policy
