#include "aia/planning/bucket_grid.h"

#include <cmath>

namespace aia {

void LatticeRect::Add(int x, int y) {
  if (empty()) {
    *this = {x, x, y, y};
  } else {
    *this = {std::min(x0, x), std::max(x1, x), std::min(y0, y),
             std::max(y1, y)};
  }
}

void BucketGrid::Reset(int nx, int ny, int count) {
  const double side = std::sqrt(2.0 * nx * ny / std::max(1, count));
  cell_ = std::clamp(static_cast<int>(std::lround(side)), 4, 64);
  gx_ = (nx + cell_ - 1) / cell_;
  gy_ = (ny + cell_ - 1) / cell_;
  begin_.assign(static_cast<std::size_t>(gx_) * gy_ + 1, 0);
}

void BucketGrid::Relabel(const std::vector<int>& ids) {
  for (int& t : items_) t = ids[t];
}

}  // namespace aia
