#include "aia/core/repeated_sum.h"

#include <cstring>

namespace aia {
namespace {

std::uint64_t Bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

double FromBits(std::uint64_t b) {
  double x;
  std::memcpy(&x, &b, sizeof x);
  return x;
}

constexpr std::uint64_t kSign = std::uint64_t{1} << 63;
constexpr std::uint64_t kFraction = (std::uint64_t{1} << 52) - 1;
constexpr std::int64_t kLow = std::int64_t{1} << 52;   // 2^e in units of u
constexpr std::int64_t kHigh = std::int64_t{1} << 53;  // 2^(e+1)

// With s normal (2^e <= |s| < 2^(e+1), whose unit in the last place is u)
// and 0 < |v| < 2^e: every addition of v to an s of this binade rounds to a
// multiple of u, and s is one, so s + v rounds as v does, by the same q
// units each time while the exact sum stays inside the binade (unless v is
// half way between two multiples: round to even then depends on s; from an
// even s it is the even one of the two every time, and s stays even). The
// additions (at most `count`) that can be taken at once, and s after them;
// none where the first could leave the binade or is a tie from an odd s.
std::int64_t BinadeRun(std::uint64_t sb, std::uint64_t vb, std::int64_t count,
                       double* s) {
  const int se = static_cast<int>(sb >> 52 & 0x7ff);
  const int ve = static_cast<int>(vb >> 52 & 0x7ff);
  const std::int64_t units = static_cast<std::int64_t>(sb & kFraction) | kLow;
  // |v| in units of u: m / 2^shift, m its integer significand.
  const std::uint64_t m =
      ve == 0 ? (vb & kFraction) : ((vb & kFraction) | kLow);
  const int shift = se - (ve == 0 ? 1 : ve);
  std::int64_t whole;  // the integer part of |v| / u
  int half;            // the rest against one half: -1 below, 0 at, 1 above
  bool exact;          // no rest
  if (shift >= 64) {
    whole = 0;
    half = -1;
    exact = false;
  } else if (shift == 0) {
    whole = static_cast<std::int64_t>(m);
    half = -1;
    exact = true;
  } else {
    whole = static_cast<std::int64_t>(m >> shift);
    const std::uint64_t rest = m & ((std::uint64_t{1} << shift) - 1);
    const std::uint64_t mid = std::uint64_t{1} << (shift - 1);
    half = rest < mid ? -1 : (rest == mid ? 0 : 1);
    exact = rest == 0;
  }
  std::int64_t q = whole + (half > 0 ? 1 : 0);  // |v| rounded, in units
  if (half == 0) {
    if (units % 2 != 0) return 0;
    q = whole % 2 == 0 ? whole : whole + 1;
  }
  if (q == 0) return 0;  // s + v rounds back to s: the caller's fixed point
  // Away from zero (v of s's sign) or toward it; the room in steps, step j
  // starting at units + j q (toward zero: minus).
  const bool away = (sb & kSign) == (vb & kSign);
  const std::int64_t room =
      away ? kHigh - units - whole - 1 : units - kLow - whole - (exact ? 0 : 1);
  if (room < 0) return 0;
  std::int64_t steps = room / q + 1;
  if (steps > count) steps = count;
  const std::int64_t after = away ? units + steps * q : units - steps * q;
  // after is in [2^52, 2^53]: 2^53 is 2^(e+1) (infinity past the largest
  // binade, as the additions would round).
  const std::uint64_t sign = sb & kSign;
  *s = after == kHigh
           ? FromBits(sign | (static_cast<std::uint64_t>(se + 1) << 52))
           : FromBits(sign | (static_cast<std::uint64_t>(se) << 52) |
                      (static_cast<std::uint64_t>(after) & kFraction));
  return steps;
}

}  // namespace

double AddRepeated(double s, double v, std::int64_t count) {
  while (count > 0) {
    const std::uint64_t sb = Bits(s), vb = Bits(v);
    const int se = static_cast<int>(sb >> 52 & 0x7ff);
    const int ve = static_cast<int>(vb >> 52 & 0x7ff);
    // s normal and finite, v finite, nonzero and below s's binade.
    if (se != 0 && se != 0x7ff && ve < se && (vb & ~kSign) != 0) {
      const std::int64_t steps = BinadeRun(sb, vb, count, &s);
      if (steps > 0) {
        count -= steps;
        continue;
      }
    }
    const double next = s + v;
    --count;
    if (Bits(next) == Bits(s)) return s;  // the same s, the same next: forever
    s = next;
  }
  return s;
}

}  // namespace aia
