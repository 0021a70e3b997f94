// Planar geometry on axis-aligned boxes: the only obstacle shape in aia (map
// images are merged into boxes), so every geometric query is exact.
#ifndef AIA_CORE_GEOMETRY_H_
#define AIA_CORE_GEOMETRY_H_

#include <cstdint>
#include <cstring>
#include <functional>
#include <utility>
#include <vector>

#include "aia/core/types.h"

namespace aia {

// Axis-aligned box [lo, hi].
struct Box {
  Vec2 lo{0.0, 0.0};
  Vec2 hi{0.0, 0.0};

  static Box FromCenterSize(const Vec2& center, const Vec2& size) {
    return {center - 0.5 * size, center + 0.5 * size};
  }
  Vec2 Center() const { return 0.5 * (lo + hi); }
  Vec2 Size() const { return hi - lo; }
  bool Contains(const Vec2& p) const {
    return p.x() >= lo.x() && p.x() <= hi.x() && p.y() >= lo.y() &&
           p.y() <= hi.y();
  }
};

// Squared distance from a point to a box (0 inside).
double PointBoxDistanceSq(const Vec2& p, const Box& b);

// Smallest distance between the segment [a, b] and the box (0 if they meet).
double SegmentBoxDistance(const Vec2& a, const Vec2& b, const Box& box);

// Whether the segment [a, b] meets the box (slab test).
bool SegmentIntersectsBox(const Vec2& a, const Vec2& b, const Box& box);

// A point by the bits of its coordinates, as the key of a table of
// answers per exact point (the claims' fields per aim, the reach channel's
// observation pixels per point).
using PointKey = std::pair<std::uint64_t, std::uint64_t>;
inline PointKey KeyOf(const Vec2& p) {
  PointKey key;
  std::memcpy(&key.first, &p.x(), sizeof(double));
  std::memcpy(&key.second, &p.y(), sizeof(double));
  return key;
}
struct PointKeyHash {
  std::size_t operator()(const PointKey& a) const {
    return std::hash<std::uint64_t>()(a.first * 0x9E3779B97F4A7C15ull ^
                                      a.second);
  }
};

}  // namespace aia

#endif  // AIA_CORE_GEOMETRY_H_
