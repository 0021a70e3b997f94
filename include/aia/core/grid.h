// A dense 2-D grid over the workspace [0, nx*cell] x [0, ny*cell], row-major
// with y rows (row 0 at y = 0). Used for occupancy, heatmaps and distance
// fields.
#ifndef AIA_CORE_GRID_H_
#define AIA_CORE_GRID_H_

#include <algorithm>
#include <cmath>
#include <vector>

#include "aia/core/check.h"
#include "aia/core/types.h"

namespace aia {

// floor(v) clamped to [0, n - 1], clamped before the conversion to int (a
// far-away estimate would overflow it); NaN gives 0.
inline int FloorIndex(double v, int n) {
  if (!(v >= 0.0)) return 0;
  const double f = std::floor(v);
  return f >= n - 1 ? n - 1 : static_cast<int>(f);
}

template <typename T>
class Grid {
 public:
  Grid() = default;
  Grid(int nx, int ny, double cell, T fill = T{})
      : nx_(nx),
        ny_(ny),
        cell_(cell),
        data_(static_cast<size_t>(nx) * ny, fill) {
    AIA_CHECK(nx >= 0 && ny >= 0 && cell > 0.0);
  }

  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double cell() const { return cell_; }
  size_t size() const { return data_.size(); }

  bool InBounds(int ix, int iy) const {
    return ix >= 0 && iy >= 0 && ix < nx_ && iy < ny_;
  }
  size_t Index(int ix, int iy) const {
    return static_cast<size_t>(iy) * nx_ + ix;
  }
  T& operator()(int ix, int iy) { return data_[Index(ix, iy)]; }
  const T& operator()(int ix, int iy) const { return data_[Index(ix, iy)]; }

  // Centre of a cell in metres.
  Vec2 CellCenter(int ix, int iy) const {
    return {(ix + 0.5) * cell_, (iy + 0.5) * cell_};
  }
  // Cell holding a point, clamped into the grid.
  void CellOf(const Vec2& p, int* ix, int* iy) const {
    *ix = FloorIndex(p.x() / cell_, nx_);
    *iy = FloorIndex(p.y() / cell_, ny_);
  }

  std::vector<T>& data() { return data_; }
  const std::vector<T>& data() const { return data_; }

 private:
  int nx_ = 0;
  int ny_ = 0;
  double cell_ = 1.0;
  std::vector<T> data_;
};

}  // namespace aia

#endif  // AIA_CORE_GRID_H_
