#include "aia/core/repeated_sum.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace aia {
namespace {

double Loop(double s, double v, std::int64_t count) {
  for (std::int64_t i = 0; i < count; ++i) s += v;
  return s;
}

std::uint64_t Bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

void ExpectSame(double s, double v, std::int64_t count) {
  const double want = Loop(s, v, count), got = AddRepeated(s, v, count);
  if (std::isnan(want)) {
    EXPECT_TRUE(std::isnan(got)) << s << " + " << count << " x " << v;
    return;
  }
  EXPECT_EQ(Bits(got), Bits(want))
      << std::hexfloat << s << " + " << count << " x " << v << ": " << got
      << " against " << want;
}

TEST(AddRepeated, WorkedByHand) {
  EXPECT_EQ(AddRepeated(1.0, 1.0, 0), 1.0);
  EXPECT_EQ(AddRepeated(1.0, 1.0, 9), 10.0);
  EXPECT_EQ(AddRepeated(0.0, 0.25, 4), 1.0);
  // 2^53 + 1 rounds back to 2^53 (a tie, to even): a fixed point.
  EXPECT_EQ(AddRepeated(0x1p53, 1.0, 1000), 0x1p53);
  // 2^53 + 3 is a tie between 2^53 + 2 and 2^53 + 4: the even mantissa,
  // 2^53 + 4; from there + 4 each time.
  EXPECT_EQ(AddRepeated(0x1p53, 3.0, 1), 0x1p53 + 4.0);
  EXPECT_EQ(AddRepeated(0x1p53, 3.0, 10), 0x1p53 + 40.0);
  // 0.1 ten times is not 1.
  EXPECT_EQ(AddRepeated(0.0, 0.1, 10), 0.9999999999999999);
  EXPECT_EQ(AddRepeated(-0.0, 0.0, 1), 0.0);
  EXPECT_FALSE(std::signbit(AddRepeated(-0.0, 0.0, 3)));
  EXPECT_TRUE(std::signbit(AddRepeated(-0.0, -0.0, 3)));
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(AddRepeated(1.0, inf, 5), inf);
  EXPECT_TRUE(std::isnan(AddRepeated(inf, -inf, 5)));
  const double max = std::numeric_limits<double>::max();
  EXPECT_EQ(AddRepeated(max, max * 0x1p-60, 1000), max);  // under half a unit
  EXPECT_EQ(AddRepeated(max * 0.5, max * 0x1p-30, 1 << 30), inf);
}

// Against the loop, over sums like the DKF's (many equal terms of one
// sign or mixed, starts of either sign), ties forced, zero crossed.
TEST(AddRepeated, EqualsTheLoopBitForBit) {
  std::mt19937_64 gen(20261208);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> exp(-40, 40), counts(0, 3000);
  for (int t = 0; t < 50000; ++t) {
    double s = std::ldexp(unit(gen), exp(gen));
    double v = std::ldexp(unit(gen), exp(gen));
    switch (t % 10) {
      case 0:
        v = s * unit(gen) * 1e-3;
        break;  // small terms
      case 1:
        v = -s * std::fabs(unit(gen)) * 1e-4;
        break;  // toward zero
      case 2:
        s = 0.0;
        break;
      case 3: {  // a tie in s's binade: v = (k + 1/2) units
        const int e = std::ilogb(s);
        v = std::ldexp(std::floor(std::fabs(unit(gen)) * 64) + 0.5, e - 52);
        if (t % 16 == 3) v = -v;
        break;
      }
      case 4:
        v = std::ldexp(std::round(unit(gen) * 1000), exp(gen));
        break;
      case 5:
        s = std::ldexp(1.0, exp(gen));
        break;  // at a binade's edge
      case 6:
        s = -std::ldexp(1.0, exp(gen));
        v = -v;
        break;
      case 7: {  // about one unit of s, either side: q of 0, 1 or 2
        const int e = std::ilogb(s);
        v = std::ldexp(unit(gen) * 4.0, e - 52);
        break;
      }
      case 8:
        v = std::ldexp(unit(gen), std::ilogb(s) - 55 - t % 40);
        break;
      default:
        break;
    }
    ExpectSame(s, v, counts(gen));
    if (HasFailure()) return;
  }
}

TEST(AddRepeated, SubnormalsAndTheRangesEnds) {
  const double tiny = std::numeric_limits<double>::denorm_min();
  ExpectSame(0.0, tiny, 100);
  ExpectSame(0x1p-1022, -tiny, 100);
  ExpectSame(0x1p-1022 - 3 * tiny, tiny, 100);
  ExpectSame(std::numeric_limits<double>::max() * 0.5,
             std::numeric_limits<double>::max() * 0x1p-20, 100000);
  ExpectSame(-std::numeric_limits<double>::max() * 0.5,
             -std::numeric_limits<double>::max() * 0x1p-20, 100000);
  ExpectSame(1.0, 0x1p-60, 5000);  // below half a unit: never moves
  ExpectSame(3.0, -1.0, 10);       // through zero
}

}  // namespace
}  // namespace aia
