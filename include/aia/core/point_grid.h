// Points hashed into square cells, for "every point within r of p" queries in
// O(points near p) instead of O(all points): the range graph's pairs and the
// sensor's robot-target pairs. Cells are at least the query radius wide, and
// fewer than 4 per point however small the radius, so the 3 x 3 cells around
// p hold every point within the radius.
#ifndef AIA_CORE_POINT_GRID_H_
#define AIA_CORE_POINT_GRID_H_

#include <cstdint>
#include <vector>

#include "aia/core/types.h"

namespace aia {

class PointGrid {
 public:
  // Indexes points[i] for the i with keep[i] (all when keep is null), for
  // queries of radius up to `radius`. Reuses its memory.
  void Build(const std::vector<Vec2>& points, double radius,
             const std::vector<std::uint8_t>* keep = nullptr);

  // Appends to `out` the indices of the indexed points within `radius`
  // (squared distance (points[j] - p).squaredNorm() <= radius^2 exactly as
  // written, so callers' own tests agree), ascending.
  void Near(const std::vector<Vec2>& points, const Vec2& p, double radius,
            std::vector<int>* out) const;

 private:
  void CellOf(const Vec2& p, int* cx, int* cy) const;

  double x0_ = 0.0, y0_ = 0.0, cell_ = 1.0;
  int nx_ = 0, ny_ = 0;
  std::vector<int> start_, fill_, items_;
};

}  // namespace aia

#endif  // AIA_CORE_POINT_GRID_H_
