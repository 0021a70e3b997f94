// Explicit, seedable random streams. No global RNG anywhere in aia: every
// consumer receives its own stream, derived from the scenario seed and a
// stream name (and an index, e.g. the robot id). Distributions are written out
// here rather than taken from <random>, whose distributions differ between
// standard libraries, so that the same seed gives the same numbers everywhere.
#ifndef AIA_CORE_RNG_H_
#define AIA_CORE_RNG_H_

#include <cstdint>
#include <string_view>

namespace aia {

// 64-bit mixer (SplitMix64 finalizer); also used to hash stream names.
std::uint64_t Mix64(std::uint64_t x);
std::uint64_t HashName(std::string_view name);

// xoshiro256** generator.
class Rng {
 public:
  explicit Rng(std::uint64_t seed = 0);
  // The stream `name`/`index` of a run seeded with `seed`. Streams with
  // different names or indices are statistically independent.
  Rng(std::uint64_t seed, std::string_view name, std::uint64_t index = 0);

  std::uint64_t Next();
  // Uniform in [0, 1).
  double Uniform();
  // Uniform in [lo, hi).
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Uniform integer in [0, n); n > 0.
  std::uint64_t UniformInt(std::uint64_t n);
  // Standard normal.
  double Normal();
  // Poisson with mean lambda >= 0.
  int Poisson(double lambda);
  // True with probability p.
  bool Bernoulli(double p) { return Uniform() < p; }

 private:
  std::uint64_t s_[4];
};

}  // namespace aia

#endif  // AIA_CORE_RNG_H_
