#include "aia/core/rng.h"

#include <cmath>

#include "aia/core/check.h"

namespace aia {
namespace {
inline std::uint64_t Rotl(std::uint64_t x, int k) {
  return (x << k) | (x >> (64 - k));
}
}  // namespace

std::uint64_t Mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::uint64_t HashName(std::string_view name) {
  std::uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a
  for (unsigned char c : name) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return Mix64(h);
}

Rng::Rng(std::uint64_t seed) {
  std::uint64_t x = seed;
  for (auto& s : s_) {
    x = Mix64(x);
    s = x;
  }
  if ((s_[0] | s_[1] | s_[2] | s_[3]) == 0) s_[0] = 1;
}

Rng::Rng(std::uint64_t seed, std::string_view name, std::uint64_t index)
    : Rng(Mix64(seed) ^ HashName(name) ^
          Mix64(index * 0x632be59bd9b4e019ULL + 1)) {}

std::uint64_t Rng::Next() {
  const std::uint64_t result = Rotl(s_[1] * 5, 7) * 9;
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = Rotl(s_[3], 45);
  return result;
}

double Rng::Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }

std::uint64_t Rng::UniformInt(std::uint64_t n) {
  AIA_CHECK(n > 0);
  // Rejection sampling on the top bits: unbiased and deterministic.
  const std::uint64_t limit = UINT64_MAX - UINT64_MAX % n;
  std::uint64_t x;
  do {
    x = Next();
  } while (x >= limit);
  return x % n;
}

double Rng::Normal() {
  // Marsaglia's polar method; the second variate is dropped so that the
  // stream has no hidden state beyond the generator's.
  double u, v, s;
  do {
    u = 2.0 * Uniform() - 1.0;
    v = 2.0 * Uniform() - 1.0;
    s = u * u + v * v;
  } while (s >= 1.0 || s == 0.0);
  return u * std::sqrt(-2.0 * std::log(s) / s);
}

int Rng::Poisson(double lambda) {
  AIA_CHECK(lambda >= 0.0);
  int total = 0;
  while (lambda > 30.0) {  // sum of Poissons; keeps exp() away from underflow
    total += Poisson(30.0);
    lambda -= 30.0;
  }
  const double limit = std::exp(-lambda);  // Knuth
  double p = Uniform();
  while (p > limit) {
    ++total;
    p *= Uniform();
  }
  return total;
}

}  // namespace aia
