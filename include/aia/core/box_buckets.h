// Items with a rectangular extent (obstacle boxes, MuJoCo geoms' bounds) in
// square buckets, for "which items may meet this rectangle" queries in
// O(items near it) instead of O(all items): the map's line of sight and
// free-point tests, and the simulation's exact rays. Coordinates outside
// the bucketed area fall into its border buckets, items and queries alike,
// so a query never misses an item whose rectangle meets it.
#ifndef AIA_CORE_BOX_BUCKETS_H_
#define AIA_CORE_BOX_BUCKETS_H_

#include <vector>

#include "aia/core/geometry.h"
#include "aia/core/types.h"

namespace aia {

class BoxBuckets {
 public:
  // Items i with rectangles bounds[i] over the area [lo, hi], buckets of
  // `cell` metres (larger where the area would need more than about 1e6).
  void Build(const Vec2& lo, const Vec2& hi, double cell,
             const std::vector<Box>& bounds);

  // Whether pred(i) holds for an item of a bucket that meets [lo, hi]; the
  // items of those buckets in bucket order, an item that spans several
  // buckets possibly more than once. False when nothing was built.
  template <typename Pred>
  bool Any(const Vec2& lo, const Vec2& hi, Pred&& pred) const;

  double cell() const { return cell_; }

 private:
  // The buckets covering [lo, hi], clamped to the grid.
  void Range(const Vec2& lo, const Vec2& hi, int* x0, int* x1, int* y0,
             int* y1) const;

  Vec2 origin_{0.0, 0.0};
  double cell_ = 1.0;
  int nx_ = 0, ny_ = 0;
  std::vector<int> start_, items_;  // CSR: bucket b holds start_[b]..[b+1]
};

template <typename Pred>
bool BoxBuckets::Any(const Vec2& lo, const Vec2& hi, Pred&& pred) const {
  if (nx_ == 0) return false;
  int x0, x1, y0, y1;
  Range(lo, hi, &x0, &x1, &y0, &y1);
  for (int iy = y0; iy <= y1; ++iy) {
    for (int ix = x0; ix <= x1; ++ix) {
      const int b = iy * nx_ + ix;
      for (int t = start_[b]; t < start_[b + 1]; ++t)
        if (pred(items_[t])) return true;
    }
  }
  return false;
}

}  // namespace aia

#endif  // AIA_CORE_BOX_BUCKETS_H_
