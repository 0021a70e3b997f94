#include "aia/core/box_buckets.h"

#include <algorithm>
#include <cmath>

namespace aia {

void BoxBuckets::Build(const Vec2& lo, const Vec2& hi, double cell,
                       const std::vector<Box>& bounds) {
  origin_ = lo;
  const Vec2 size = (hi - lo).cwiseMax(Vec2(0.0, 0.0));
  cell_ = std::max(cell, std::sqrt(size.x() * size.y() / 1e6));
  nx_ = std::max(1, static_cast<int>(std::ceil(size.x() / cell_)));
  ny_ = std::max(1, static_cast<int>(std::ceil(size.y() / cell_)));
  start_.assign(static_cast<size_t>(nx_) * ny_ + 1, 0);
  const auto each = [&](auto&& visit) {
    for (int i = 0; i < static_cast<int>(bounds.size()); ++i) {
      int x0, x1, y0, y1;
      Range(bounds[i].lo, bounds[i].hi, &x0, &x1, &y0, &y1);
      for (int iy = y0; iy <= y1; ++iy)
        for (int ix = x0; ix <= x1; ++ix) visit(iy * nx_ + ix, i);
    }
  };
  each([&](int b, int) { ++start_[b + 1]; });
  for (size_t b = 1; b < start_.size(); ++b) start_[b] += start_[b - 1];
  items_.resize(start_.back());
  std::vector<int> fill(start_.begin(), start_.end() - 1);
  each([&](int b, int i) { items_[fill[b]++] = i; });
}

void BoxBuckets::Range(const Vec2& lo, const Vec2& hi, int* x0, int* x1,
                       int* y0, int* y1) const {
  const auto bucket = [this](double v, double o, int n) {
    const double b = std::floor((v - o) / cell_);
    if (!(b > 0.0)) return 0;  // NaN too
    return b >= n - 1 ? n - 1 : static_cast<int>(b);
  };
  *x0 = bucket(lo.x(), origin_.x(), nx_);
  *x1 = bucket(hi.x(), origin_.x(), nx_);
  *y0 = bucket(lo.y(), origin_.y(), ny_);
  *y1 = bucket(hi.y(), origin_.y(), ny_);
}

}  // namespace aia
