#include "aia/core/point_grid.h"

#include <algorithm>
#include <cmath>

namespace aia {

void PointGrid::Build(const std::vector<Vec2>& points, double radius,
                      const std::vector<std::uint8_t>* keep) {
  const int n = static_cast<int>(points.size());
  bool any = false;
  double x1 = 0.0, y1 = 0.0;
  int count = 0;
  for (int i = 0; i < n; ++i) {
    if (keep && !(*keep)[i]) continue;
    const Vec2& p = points[i];
    if (!any) {
      x0_ = x1 = p.x();
      y0_ = y1 = p.y();
      any = true;
    }
    x0_ = std::min(x0_, p.x());
    x1 = std::max(x1, p.x());
    y0_ = std::min(y0_, p.y());
    y1 = std::max(y1, p.y());
    ++count;
  }
  nx_ = ny_ = 0;
  items_.clear();
  if (!any) return;
  const double extent = std::max({x1 - x0_, y1 - y0_, 1e-9});
  const double side_cap = 2.0 * std::sqrt(static_cast<double>(count)) + 1.0;
  cell_ = std::max(radius, extent / side_cap);
  nx_ = static_cast<int>((x1 - x0_) / cell_) + 1;
  ny_ = static_cast<int>((y1 - y0_) / cell_) + 1;
  // Counting sort by cell (compressed rows).
  start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
  for (int i = 0; i < n; ++i) {
    if (keep && !(*keep)[i]) continue;
    int cx = 0, cy = 0;
    CellOf(points[i], &cx, &cy);
    ++start_[static_cast<std::size_t>(cy) * nx_ + cx + 1];
  }
  for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  items_.resize(start_.back());
  fill_.assign(start_.begin(), start_.end() - 1);
  for (int i = 0; i < n; ++i) {
    if (keep && !(*keep)[i]) continue;
    int cx = 0, cy = 0;
    CellOf(points[i], &cx, &cy);
    items_[fill_[static_cast<std::size_t>(cy) * nx_ + cx]++] = i;
  }
}

void PointGrid::CellOf(const Vec2& p, int* cx, int* cy) const {
  // Clamped: a query point may lie outside the indexed points' box.
  const double fx = std::floor((p.x() - x0_) / cell_);
  const double fy = std::floor((p.y() - y0_) / cell_);
  *cx = fx < 0.0 ? -1 : fx >= nx_ ? nx_ : static_cast<int>(fx);
  *cy = fy < 0.0 ? -1 : fy >= ny_ ? ny_ : static_cast<int>(fy);
}

void PointGrid::Near(const std::vector<Vec2>& points, const Vec2& p,
                     double radius, std::vector<int>* out) const {
  if (nx_ == 0) return;
  int cx = 0, cy = 0;
  CellOf(p, &cx, &cy);
  const double r2 = radius * radius;
  const std::size_t first = out->size();
  for (int y = std::max(0, cy - 1); y <= std::min(ny_ - 1, cy + 1); ++y) {
    for (int x = std::max(0, cx - 1); x <= std::min(nx_ - 1, cx + 1); ++x) {
      const std::size_t c = static_cast<std::size_t>(y) * nx_ + x;
      for (int e = start_[c]; e < start_[c + 1]; ++e) {
        const int j = items_[e];
        if ((points[j] - p).squaredNorm() <= r2) out->push_back(j);
      }
    }
  }
  std::sort(out->begin() + first, out->end());
}

}  // namespace aia
