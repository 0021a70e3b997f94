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
  bucket_ = std::max(1.0, std::sqrt(size_.x() * size_.y() / 1e6));
  bx_ = std::max(1, static_cast<int>(std::ceil(size_.x() / bucket_)));
  by_ = std::max(1, static_cast<int>(std::ceil(size_.y() / bucket_)));
  buckets_.assign(static_cast<size_t>(bx_) * by_, {});
  for (int b = 0; b < static_cast<int>(obstacles_.size()); ++b) {
    const Box& box = obstacles_[b];
    int x0, x1, y0, y1;
    BucketRange(box.lo, box.hi, &x0, &x1, &y0, &y1);
    for (int iy = y0; iy <= y1; ++iy)
      for (int ix = x0; ix <= x1; ++ix)
        buckets_[static_cast<size_t>(iy) * bx_ + ix].push_back(b);
  }
}

void Map::BucketRange(const Vec2& lo, const Vec2& hi, int* x0, int* x1, int* y0,
                      int* y1) const {
  const auto bucket = [this](double v, int n) {
    return static_cast<int>(
        std::clamp(std::floor(v / bucket_), 0.0, static_cast<double>(n - 1)));
  };
  *x0 = bucket(lo.x(), bx_);
  *x1 = bucket(hi.x(), bx_);
  *y0 = bucket(lo.y(), by_);
  *y1 = bucket(hi.y(), by_);
}

bool Map::LineOfSight(const Vec2& a, const Vec2& b) const {
  int x0, x1, y0, y1;
  BucketRange(a.cwiseMin(b), a.cwiseMax(b), &x0, &x1, &y0, &y1);
  for (int iy = y0; iy <= y1; ++iy) {
    for (int ix = x0; ix <= x1; ++ix) {
      for (int bi : buckets_[static_cast<size_t>(iy) * bx_ + ix]) {
        if (SegmentIntersectsBox(a, b, obstacles_[bi])) return false;
      }
    }
  }
  return true;
}

bool Map::PointFree(const Vec2& p) const {
  if (p.x() < 0.0 || p.y() < 0.0 || p.x() > size_.x() || p.y() > size_.y())
    return false;
  for (const Box& b : obstacles_)
    if (b.Contains(p)) return false;
  return true;
}

}  // namespace aia
