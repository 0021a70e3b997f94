#include "aia/core/box_buckets.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "aia/core/rng.h"

namespace aia {
namespace {

// Every item whose rectangle meets the query's, found by a loop over all.
std::vector<int> Meeting(const std::vector<Box>& items, const Vec2& lo,
                         const Vec2& hi) {
  std::vector<int> out;
  for (int i = 0; i < static_cast<int>(items.size()); ++i)
    if (items[i].lo.x() <= hi.x() && lo.x() <= items[i].hi.x() &&
        items[i].lo.y() <= hi.y() && lo.y() <= items[i].hi.y())
      out.push_back(i);
  return out;
}

TEST(BoxBucketsTest, AQueryVisitsEveryItemItsRectangleMeets) {
  // Items and queries inside, across and outside the bucketed area (border
  // buckets take what lies beyond it).
  Rng rng(3);
  std::vector<Box> items;
  for (int i = 0; i < 200; ++i) {
    const Vec2 c(rng.Uniform(-3.0, 23.0), rng.Uniform(-3.0, 23.0));
    const Vec2 h(rng.Uniform(0.0, 2.5), rng.Uniform(0.0, 2.5));
    items.push_back({c - h, c + h});
  }
  BoxBuckets buckets;
  buckets.Build(Vec2(0.0, 0.0), Vec2(20.0, 20.0), 1.0, items);
  for (int q = 0; q < 500; ++q) {
    const Vec2 a(rng.Uniform(-5.0, 25.0), rng.Uniform(-5.0, 25.0));
    const Vec2 b = a + Vec2(rng.Uniform(0.0, 4.0), rng.Uniform(0.0, 4.0));
    std::vector<int> seen;
    buckets.Any(a, b, [&](int i) {
      seen.push_back(i);
      return false;
    });
    for (int i : Meeting(items, a, b))
      EXPECT_NE(std::find(seen.begin(), seen.end(), i), seen.end())
          << "item " << i << " missed by the query at " << a.transpose();
  }
}

TEST(BoxBucketsTest, AnyStopsAtTheFirstYesAndAnEmptyIndexSaysNo) {
  BoxBuckets buckets;
  EXPECT_FALSE(buckets.Any(Vec2(0, 0), Vec2(1, 1), [](int) { return true; }));
  buckets.Build(Vec2(0, 0), Vec2(4, 4), 1.0,
                {{Vec2(0.2, 0.2), Vec2(3.8, 0.4)}, {Vec2(1, 1), Vec2(2, 2)}});
  int calls = 0;
  EXPECT_TRUE(buckets.Any(Vec2(0, 0), Vec2(4, 4), [&](int) {
    ++calls;
    return true;
  }));
  EXPECT_EQ(calls, 1);
  // A NaN query lands in a border bucket, not out of bounds.
  EXPECT_FALSE(
      buckets.Any(Vec2(NAN, NAN), Vec2(NAN, NAN), [](int i) { return i > 5; }));
  // A huge area is held to about 1e6 buckets.
  buckets.Build(Vec2(0, 0), Vec2(1e5, 1e5), 1.0, {});
  EXPECT_GE(buckets.cell(), 100.0);
}

}  // namespace
}  // namespace aia
