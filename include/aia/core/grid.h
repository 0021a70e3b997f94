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
    *ix = std::clamp(static_cast<int>(std::floor(p.x() / cell_)), 0, nx_ - 1);
    *iy = std::clamp(static_cast<int>(std::floor(p.y() / cell_)), 0, ny_ - 1);
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
