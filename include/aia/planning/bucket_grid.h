// Items (targets, robots) in square buckets of lattice points, as CSR: the
// sampling tree's spatial indexes (planning/sampling_tree.h, docs/design.md,
// Policies), searched ring by ring around a point or a rectangle.
#ifndef AIA_PLANNING_BUCKET_GRID_H_
#define AIA_PLANNING_BUCKET_GRID_H_

#include <algorithm>
#include <vector>

namespace aia {

// A rectangle of lattice coordinates (x0 > x1: empty).
struct LatticeRect {
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;

  bool empty() const { return x0 > x1; }
  // Grown to hold (x, y).
  void Add(int x, int y);
  // L1 distance (lattice steps) from (x, y): a lower bound of the BFS
  // distance to any point in it, each move changing one coordinate by one.
  int Distance(int x, int y) const {
    return std::max({0, x0 - x, x - x1}) + std::max({0, y0 - y, y - y1});
  }
};

class BucketGrid {
 public:
  // Sized for about two of `count` items per bucket over nx x ny lattice
  // points, and filled with the items t in [0, count) for which
  // bucket_of(t) (Of() of the item's point) is not -1, in increasing order
  // within a bucket.
  template <typename BucketOf>
  void Fill(int nx, int ny, int count, BucketOf&& bucket_of);
  // Each item t replaced by ids[t].
  void Relabel(const std::vector<int>& ids);

  // The bucket of lattice point (x, y).
  int Of(int x, int y) const { return (y / cell_) * gx_ + x / cell_; }
  int cell() const { return cell_; }
  // Rings enough to cover the grid from any bucket.
  int rings() const { return std::max(gx_, gy_); }

  // Calls visit(item) for the items of the buckets at Chebyshev distance r
  // from the bucket rectangle [bx0, bx1] x [by0, by1] (the rectangle itself
  // for r = 0), clipped to the grid, bucket by bucket in row order.
  template <typename Visit>
  void VisitRing(int bx0, int bx1, int by0, int by1, int r,
                 Visit&& visit) const;

 private:
  void Reset(int nx, int ny, int count);

  int cell_ = 8, gx_ = 0, gy_ = 0;  // bucket side (lattice points), buckets
  std::vector<int> begin_, items_, fill_;
};

template <typename BucketOf>
void BucketGrid::Fill(int nx, int ny, int count, BucketOf&& bucket_of) {
  Reset(nx, ny, count);
  for (int t = 0; t < count; ++t) {
    const int b = bucket_of(t);
    if (b >= 0) ++begin_[b + 1];
  }
  for (std::size_t c = 1; c < begin_.size(); ++c) begin_[c] += begin_[c - 1];
  items_.resize(begin_.back());
  fill_.assign(begin_.begin(), begin_.end() - 1);
  for (int t = 0; t < count; ++t) {
    const int b = bucket_of(t);
    if (b >= 0) items_[fill_[b]++] = t;
  }
}

template <typename Visit>
void BucketGrid::VisitRing(int bx0, int bx1, int by0, int by1, int r,
                           Visit&& visit) const {
  const auto bucket = [&](int c) {
    for (int t = begin_[c]; t < begin_[c + 1]; ++t) visit(items_[t]);
  };
  const int x0 = bx0 - r, x1 = bx1 + r, y0 = by0 - r, y1 = by1 + r;
  for (int y = std::max(0, y0); y <= std::min(gy_ - 1, y1); ++y) {
    if (r == 0 || y == y0 || y == y1) {
      for (int x = std::max(0, x0); x <= std::min(gx_ - 1, x1); ++x)
        bucket(y * gx_ + x);
    } else {
      if (x0 >= 0) bucket(y * gx_ + x0);
      if (x1 < gx_) bucket(y * gx_ + x1);
    }
  }
}

}  // namespace aia

#endif  // AIA_PLANNING_BUCKET_GRID_H_
