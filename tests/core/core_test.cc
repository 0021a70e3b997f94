#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "aia/core/error.h"
#include "aia/core/geometry.h"
#include "aia/core/grid.h"
#include "aia/core/point_grid.h"
#include "aia/core/rng.h"

namespace aia {
namespace {

TEST(RngTest, SameSeedAndStreamGiveSameNumbers) {
  Rng a(42, "sensor", 3), b(42, "sensor", 3);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(a.Next(), b.Next());
}

TEST(RngTest, StreamsDiffer) {
  Rng a(42, "sensor", 3), b(42, "sensor", 4), c(42, "policy", 3),
      d(43, "sensor", 3);
  const auto x = a.Next();
  EXPECT_NE(x, b.Next());
  EXPECT_NE(x, c.Next());
  EXPECT_NE(x, d.Next());
}

TEST(RngTest, UniformIntCoversRangeEvenly) {
  Rng r(1);
  int counts[5] = {0};
  for (int i = 0; i < 50000; ++i) ++counts[r.UniformInt(5)];
  for (int c : counts) EXPECT_NEAR(c, 10000, 400);
}

TEST(RngTest, NormalHasUnitMoments) {
  Rng r(2);
  double s = 0, s2 = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double x = r.Normal();
    s += x;
    s2 += x * x;
  }
  EXPECT_NEAR(s / n, 0.0, 0.02);
  EXPECT_NEAR(s2 / n, 1.0, 0.02);
}

TEST(RngTest, PoissonMeanMatchesLambda) {
  for (double lambda : {0.0, 1.0, 4.5, 70.0}) {
    Rng r(3);
    double s = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) s += r.Poisson(lambda);
    EXPECT_NEAR(s / n, lambda, 0.05 * lambda + 0.02) << lambda;
  }
}

TEST(GeometryTest, PointBoxDistance) {
  const Box b{{1, 1}, {2, 3}};
  EXPECT_DOUBLE_EQ(PointBoxDistanceSq({1.5, 2}, b), 0.0);
  EXPECT_DOUBLE_EQ(PointBoxDistanceSq({0, 2}, b), 1.0);
  EXPECT_DOUBLE_EQ(PointBoxDistanceSq({3, 4}, b), 2.0);  // corner: 1^2 + 1^2
}

TEST(GeometryTest, SegmentBoxTests) {
  const Box b{{1, 1}, {2, 2}};
  EXPECT_TRUE(SegmentIntersectsBox({0, 1.5}, {3, 1.5}, b));
  EXPECT_FALSE(SegmentIntersectsBox({0, 2.5}, {3, 2.5}, b));
  EXPECT_FALSE(SegmentIntersectsBox({0, 0}, {0.9, 0.9}, b));  // stops short
  EXPECT_TRUE(SegmentIntersectsBox({0, 0}, {3, 3}, b));  // diagonal through
  EXPECT_DOUBLE_EQ(SegmentBoxDistance({0, 2.5}, {3, 2.5}, b), 0.5);
  EXPECT_DOUBLE_EQ(SegmentBoxDistance({0, 1.5}, {3, 1.5}, b), 0.0);
  // A vertical segment beside the box: closest to the box's right edge.
  EXPECT_NEAR(SegmentBoxDistance({2.3, 0}, {2.3, 3}, b), 0.3, 1e-12);
}

TEST(GridTest, CellsAndCenters) {
  Grid<int> g(4, 3, 0.5, 7);
  EXPECT_EQ(g.size(), 12u);
  EXPECT_EQ(g(3, 2), 7);
  int ix, iy;
  g.CellOf({1.2, 0.7}, &ix, &iy);
  EXPECT_EQ(ix, 2);
  EXPECT_EQ(iy, 1);
  EXPECT_DOUBLE_EQ(g.CellCenter(2, 1).x(), 1.25);
  g.CellOf({-5, 99}, &ix, &iy);  // clamped
  EXPECT_EQ(ix, 0);
  EXPECT_EQ(iy, 2);
}

TEST(InputErrorTest, FormatsFileLineKey) {
  EXPECT_EQ(InputError("a.yaml", 4, "robots.count", "must be >= 1").Format(),
            "a.yaml:4: robots.count: must be >= 1");
  EXPECT_EQ(InputError("command line", 0, "--policy", "unknown").Format(),
            "command line: --policy: unknown");
}

// Flag() is the constructor's command-line error, field for field.
TEST(InputErrorTest, FlagIsTheCommandLine) {
  const InputError e = InputError::Flag("--policy", "unknown");
  EXPECT_EQ(e.file(), "command line");
  EXPECT_EQ(e.line(), 0);
  EXPECT_EQ(e.key(), "--policy");
  EXPECT_EQ(e.message(), "unknown");
  EXPECT_STREQ(e.what(), "command line:0: --policy: unknown");
  EXPECT_EQ(e.Format(), "command line: --policy: unknown");
}

// A message quoting odd bytes (yaml-cpp's "unknown escape character: " and
// the raw byte) still prints as one line.
TEST(InputErrorTest, FormatIsOneLine) {
  EXPECT_EQ(InputError("a\nb.yaml", 2, "(yaml)",
                       std::string("bad \x01 escape: \n\t\r\x7f\0 end", 23))
                .Format(),
            "a\\nb.yaml:2: (yaml): bad \\x01 escape: \\n\\t\\r\\x7f\\x00 end");
  EXPECT_EQ(OneLine("caf\xc3\xa9 ok"), "caf\xc3\xa9 ok");  // UTF-8 stays
  // Bytes that are not UTF-8 are escapes, never raw on a terminal (a --set
  // key or a path of another encoding was echoed as it came): a stray
  // byte, a cut sequence, an overlong form, a surrogate; four-byte UTF-8
  // stays.
  EXPECT_EQ(OneLine("see\xff"
                    "d"),
            "see\\xffd");
  EXPECT_EQ(OneLine("caf\xc3"), "caf\\xc3");
  EXPECT_EQ(OneLine("\xc0\xaf"), "\\xc0\\xaf");
  EXPECT_EQ(OneLine("\xed\xa0\x80"), "\\xed\\xa0\\x80");
  EXPECT_EQ(OneLine("\xf0\x9f\x98\x80!"), "\xf0\x9f\x98\x80!");
}

TEST(PointGridTest, NearIsEveryPointWithinTheRadiusAscending) {
  Rng rng(12);
  std::vector<Vec2> points;
  for (int i = 0; i < 500; ++i)
    points.emplace_back(rng.Uniform(-5.0, 95.0), rng.Uniform(0.0, 30.0));
  std::vector<std::uint8_t> keep(points.size(), 1);
  for (std::size_t i = 0; i < keep.size(); i += 7) keep[i] = 0;
  for (const double radius : {1e-3, 0.7, 2.0, 9.0, 1e4}) {
    for (const bool all : {true, false}) {
      PointGrid grid;
      grid.Build(points, radius, all ? nullptr : &keep);
      for (int q = 0; q < 60; ++q) {
        // Queries inside the box, on points, and far outside it.
        const Vec2 p =
            q < 20   ? points[q * 11]
            : q < 40 ? Vec2(rng.Uniform(-50.0, 150.0), rng.Uniform(-50.0, 80.0))
                     : Vec2(rng.Uniform(0.0, 90.0), rng.Uniform(0.0, 30.0));
        std::vector<int> got, want;
        grid.Near(points, p, radius, &got);
        for (int j = 0; j < static_cast<int>(points.size()); ++j)
          if ((all || keep[j]) &&
              (points[j] - p).squaredNorm() <= radius * radius)
            want.push_back(j);
        ASSERT_EQ(got, want) << "radius " << radius << ", query " << q;
      }
    }
  }
  PointGrid empty;
  empty.Build({}, 1.0);
  std::vector<int> none;
  empty.Near({}, Vec2(0, 0), 1.0, &none);
  EXPECT_TRUE(none.empty());
}

}  // namespace
}  // namespace aia
