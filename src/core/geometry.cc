#include "aia/core/geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace aia {

double PointBoxDistanceSq(const Vec2& p, const Box& b) {
  const double dx = std::max({b.lo.x() - p.x(), 0.0, p.x() - b.hi.x()});
  const double dy = std::max({b.lo.y() - p.y(), 0.0, p.y() - b.hi.y()});
  return dx * dx + dy * dy;
}

bool SegmentIntersectsBox(const Vec2& a, const Vec2& b, const Box& box) {
  double t0 = 0.0, t1 = 1.0;
  const Vec2 d = b - a;
  for (int axis = 0; axis < 2; ++axis) {
    if (std::abs(d[axis]) < 1e-15) {
      if (a[axis] < box.lo[axis] || a[axis] > box.hi[axis]) return false;
      continue;
    }
    double ta = (box.lo[axis] - a[axis]) / d[axis];
    double tb = (box.hi[axis] - a[axis]) / d[axis];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

namespace {
double PointSegmentDistanceSq(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 d = b - a;
  const double len2 = d.squaredNorm();
  double t = len2 > 0.0 ? (p - a).dot(d) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return (a + t * d - p).squaredNorm();
}
}  // namespace

double SegmentBoxDistance(const Vec2& a, const Vec2& b, const Box& box) {
  if (SegmentIntersectsBox(a, b, box)) return 0.0;
  // Disjoint convex sets: the closest pair involves an endpoint of the segment
  // or a corner of the box.
  double best =
      std::min(PointBoxDistanceSq(a, box), PointBoxDistanceSq(b, box));
  const Vec2 corners[4] = {
      box.lo, {box.hi.x(), box.lo.y()}, box.hi, {box.lo.x(), box.hi.y()}};
  for (const Vec2& c : corners)
    best = std::min(best, PointSegmentDistanceSq(c, a, b));
  return std::sqrt(best);
}

}  // namespace aia
