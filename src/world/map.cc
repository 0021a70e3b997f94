#include "aia/world/map.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace aia {
namespace {

Grid<std::uint8_t> Rasterize(const Vec2& size, double cell,
                             const std::vector<Box>& boxes) {
  const int nx =
      std::max(1, static_cast<int>(std::ceil(size.x() / cell - 1e-9)));
  const int ny =
      std::max(1, static_cast<int>(std::ceil(size.y() / cell - 1e-9)));
  Grid<std::uint8_t> grid(nx, ny, cell, 0);
  for (const Box& b : boxes) {
    // Cells whose interior overlaps the box.
    if (b.hi.x() <= 0.0 || b.hi.y() <= 0.0 || b.lo.x() >= nx * cell ||
        b.lo.y() >= ny * cell)
      continue;
    const int x0 = FloorIndex(b.lo.x() / cell, nx);
    const int y0 = FloorIndex(b.lo.y() / cell, ny);
    const int x1 = FloorIndex(std::ceil(b.hi.x() / cell) - 1, nx);
    const int y1 = FloorIndex(std::ceil(b.hi.y() / cell) - 1, ny);
    for (int iy = y0; iy <= y1; ++iy)
      for (int ix = x0; ix <= x1; ++ix) grid(ix, iy) = 1;
  }
  return grid;
}

}  // namespace

Map::Map(const Vec2& size, std::vector<Box> obstacles, double cell, double step,
         double robot_radius)
    : size_(size),
      obstacles_(std::move(obstacles)),
      occupancy_(Rasterize(size, cell, obstacles_)),
      lattice_(size, step, robot_radius, obstacles_),
      robot_radius_(robot_radius) {
  // 1 m buckets, larger in workspaces over 1 km^2 so that there are at most
  // about 1e6 of them.
  buckets_.Build(Vec2(0.0, 0.0), size_, 1.0, obstacles_);
}

bool Map::LineOfSight(const Vec2& a, const Vec2& b) const {
  return !buckets_.Any(a.cwiseMin(b), a.cwiseMax(b), [&](int i) {
    return SegmentIntersectsBox(a, b, obstacles_[i]);
  });
}

bool Map::PointFree(const Vec2& p) const {
  if (p.x() < 0.0 || p.y() < 0.0 || p.x() > size_.x() || p.y() > size_.y())
    return false;
  // A box that holds p is in p's bucket.
  return !buckets_.Any(p, p, [&](int i) { return obstacles_[i].Contains(p); });
}

}  // namespace aia
