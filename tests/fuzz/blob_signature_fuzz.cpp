// libFuzzer target: arbitrary bytes into the blob signature parser (runtime/policy/signature.hpp).
// It returns a signature or an error naming the file and the line; a signature it accepts formats
// back to the same bytes (the format has one spelling), and verifying it against a blob and a key
// it was not made with is refused, never accepted.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "runtime/policy/signature.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pbppo::policy;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto sig = ParseSignature(text, "fuzz.sig");
  if (!sig) {
    if (sig.error().message.rfind("fuzz.sig: ", 0) != 0) std::abort();
    return 0;
  }
  if (FormatSignature(*sig) != text) std::abort();
  PublicKey key;
  key.name = "k";
  key.id = sig->key_id;  // trusted by id, so the check reaches the hash and the signature
  for (std::size_t i = 0; i < key.raw.size(); ++i) key.raw[i] = static_cast<std::uint8_t>(i * 7 + 1);
  const std::uint8_t blob[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  const std::string s(text);
  if (VerifyBlob({blob, sizeof blob}, "b.blob", &s, "fuzz.sig", {&key, 1}).ok()) std::abort();
  return 0;
}
