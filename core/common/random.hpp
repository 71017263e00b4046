#pragma once
// Seeded randomness with fully specified algorithms, so a seed gives the same numbers on every
// standard library (std::uniform_int_distribution is implementation-defined; we avoid it).
#include <cmath>
#include <cstdint>
#include <numbers>

namespace rover {

// SplitMix64 (Steele, Lea & Flood 2014): a fast, well-mixed 64-bit generator; also used to derive
// independent sub-seeds from one user seed.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform integer in [0, bound), bound > 0 (Lemire's multiply-shift; bias < 2^-32 for our sizes).
  std::uint64_t below(std::uint64_t bound) {
    __extension__ using U128 = unsigned __int128;  // GCC/Clang extension, fine under -Wpedantic
    return static_cast<std::uint64_t>((static_cast<U128>(next()) * bound) >> 64);
  }
  // Uniform double in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

 private:
  std::uint64_t state_;
};

// A standard normal draw (Box–Muller, one value per call), so the stream is the same on every
// standard library (std::normal_distribution is implementation-defined too).
inline double normalDraw(Rng& rng) {
  const double u1 = 1.0 - rng.uniform();  // (0, 1]
  const double u2 = rng.uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2 * std::numbers::pi * u2);
}

// A sub-seed for a named purpose, so streams for obstacles, starts, ... never overlap.
inline std::uint64_t deriveSeed(std::uint64_t seed, std::uint64_t stream) {
  Rng r(seed ^ (stream * 0xD1B54A32D192ED03ull));
  return r.next();
}

}  // namespace rover
