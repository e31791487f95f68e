// Independent random streams from the run's one seed: Mix(seed, stream) (SplitMix64's finaliser),
// one stream per purpose (minibatch order 0, network initialisation 1, evaluation 7, environment e
// 1000 + e), so that what one part draws never shifts another's numbers.
#pragma once

#include <cstdint>

namespace pbppo::trainer {

inline std::uint64_t Mix(std::uint64_t a, std::uint64_t b) {
  std::uint64_t z = a + 0x9E3779B97F4A7C15ull * (b + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace pbppo::trainer
