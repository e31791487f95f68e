#include <doctest/doctest.h>

#include <cstring>
#include <vector>

#include "runtime/core/crc32.hpp"
#include "runtime/core/random.hpp"

using pbppo::Crc32;

TEST_CASE("crc32 matches the standard check values") {
  const char* s = "123456789";
  CHECK(Crc32(s, std::strlen(s)) == 0xCBF43926u);
  CHECK(Crc32("", 0) == 0u);
  const char* fox = "The quick brown fox jumps over the lazy dog";
  CHECK(Crc32(fox, std::strlen(fox)) == 0x414FA339u);
}

TEST_CASE("crc32 continues across chunks and agrees with a bitwise reference") {
  pbppo::Rng rng(3);
  std::vector<unsigned char> data(1031);
  for (auto& b : data) b = static_cast<unsigned char>(rng.Next());
  std::uint32_t ref = 0xFFFFFFFFu;
  for (unsigned char b : data) {
    ref ^= b;
    for (int k = 0; k < 8; ++k) ref = (ref & 1u) ? (0xEDB88320u ^ (ref >> 1)) : (ref >> 1);
  }
  ref = ~ref;
  CHECK(Crc32(data.data(), data.size()) == ref);
  for (std::size_t cut : {0u, 1u, 3u, 4u, 5u, 512u, 1030u}) {
    CHECK(Crc32(data.data() + cut, data.size() - cut, Crc32(data.data(), cut)) == ref);
  }
}

TEST_CASE("rng is deterministic and its normals have the right moments") {
  pbppo::Rng a(42), b(42), c(43);
  for (int i = 0; i < 100; ++i) CHECK(a.Next() == b.Next());
  CHECK(a.Next() != c.Next());
  pbppo::Rng r(7);
  double sum = 0, sq = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = r.Normal();
    sum += x;
    sq += x * x;
  }
  CHECK(sum / n == doctest::Approx(0.0).epsilon(0.01).scale(1.0));
  CHECK(sq / n == doctest::Approx(1.0).epsilon(0.01));
  for (int i = 0; i < 1000; ++i) CHECK(r.Below(10) < 10u);
}
