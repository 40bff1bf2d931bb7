// SPDX-License-Identifier: Apache-2.0
// Counter-based random numbers for the simulator. Every draw is a pure function of a 64-bit key
// derived from (scene seed, camera, frame, ...), so any frame can be rendered alone, in any order,
// on any thread, and give the same result.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

namespace panoptes::sim {

// Steele, Lea & Flood, "Fast splittable pseudorandom number generators" (OOPSLA 2014): a bijective
// 64-bit finaliser; used both as a hash and, over a counter, as a generator that passes BigCrush.
constexpr std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// Order matters (hash_key(a, b) != hash_key(b, a)), so (camera 1, frame 2) and (camera 2, frame 1)
// get unrelated streams.
constexpr std::uint64_t hash_key(std::uint64_t a, std::uint64_t b) {
  return splitmix64(a ^ splitmix64(b));
}
constexpr std::uint64_t hash_key(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  return hash_key(hash_key(a, b), c);
}

class Rng {
 public:
  explicit Rng(std::uint64_t key) : state_(key) {}

  std::uint64_t next() {
    state_ += 0x9E3779B97F4A7C15ULL;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }

  // Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

  // Box-Muller; only the cosine branch is used so the number of draws per call is fixed, which
  // keeps later draws of the same stream independent of how many normals were asked for before.
  double normal() {
    const double u1 = 1.0 - uniform();  // (0, 1]: log stays finite
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  std::uint64_t state_;
};

// Standard-normal quantiles at (i + 0.5) / 65536: indexing it with 16 random bits gives a normal
// deviate (tails cut at 4.3 sigma) for the price of one load, which is what per-pixel sensor noise
// needs to keep a VGA frame near a millisecond.
inline constexpr int kNormalTableBits = 16;
const float* normal_quantile_table();

// Inverse of the standard normal CDF, accurate to ~1e-15 (Acklam's rational approximation plus
// one Halley step on erfc).
double inverse_normal_cdf(double p);

}  // namespace panoptes::sim
