// The sampling tree's spatial indexes (planning/sampling_tree.h): open
// targets by the centre of their observation region and a node's robots by
// their point, in bucket grids (bucket_grid.h), and the nearest-target and
// reach queries they answer.
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "aia/core/check.h"
#include "aia/planning/information.h"
#include "aia/planning/sampling_tree.h"
#include "aia/planning/search.h"
#include "aia/world/lattice.h"
#include "sampling_tree_internal.h"

namespace aia {

// Below these sizes the spatial indexes are not worth their upkeep: a linear
// scan of the open targets, of the robots. Either way the result is the
// same.
constexpr int kLinearTargets = 32;
constexpr int kLinearRobots = 32;

void SamplingTree::BuildOpenIndex() {
  open_indexed_ =
      indexed_ && static_cast<int>(open_list_.size()) > kLinearTargets;
  if (!open_indexed_) return;
  const Lattice& lattice = problem_->map->lattice();
  BucketGrid& g = open_index_;
  // Items are positions in open_list_; the index holds target ids.
  g.Fill(lattice.nx(), lattice.ny(), static_cast<int>(open_list_.size()),
         [&](int t) {
           const LatticeRect& b = region_box_[open_list_[t]];
           if (b.empty()) return -1;  // no region: its field is -1 everywhere
           return g.Of((b.x0 + b.x1) / 2, (b.y0 + b.y1) / 2);
         });
  g.Relabel(open_list_);
}

void SamplingTree::BuildRobotIndex(const int* positions) {
  const SamplingProblem& p = *problem_;
  const Lattice& lattice = p.map->lattice();
  robots_indexed_ = indexed_ && n_ > kLinearRobots;
  if (!robots_indexed_) return;
  BucketGrid& g = robot_index_;
  g.Fill(lattice.nx(), lattice.ny(), n_, [&](int i) {
    if (!p.active[i]) return -1;
    return g.Of(lattice.Ix(positions[i]), lattice.Iy(positions[i]));
  });
}

int SamplingTree::NearestTarget(int q, int depth, const std::vector<char>& ok,
                                int* dist) {
  int best = -1, best_d = std::numeric_limits<int>::max();
  if (indexed_ && !open_indexed_) {
    // Few open targets: in order of the L1 bound of their distance, reading
    // a field (a cache miss, likely) only while it may beat the best.
    near_.clear();
    const Lattice& lattice = problem_->map->lattice();
    const int x = lattice.Ix(q), y = lattice.Iy(q);
    for (int k : open_list_) {
      const LatticeRect& b = region_box_[k];
      if (!ok[k] || b.empty()) continue;
      near_.push_back({b.Distance(x, y), k});
    }
    while (!near_.empty()) {  // the least bound next, by selection
      size_t j = 0;
      for (size_t c = 1; c < near_.size(); ++c)
        if (near_[c] < near_[j]) j = c;
      const auto [lb, k] = near_[j];
      if (best >= 0 && lb > best_d) break;
      near_[j] = near_.back();
      near_.pop_back();
      const int d = static_field_[k][q];
      if (d >= 0 && (best < 0 || d < best_d || (d == best_d && k < best))) {
        best = k;
        best_d = d;
      }
    }
    *dist = best_d;
    return best;
  }
  if (!open_indexed_) {
    for (int k : open_list_) {
      if (!ok[k]) continue;
      const int d = aims_.FieldAt(depth, k)[q];
      if (d >= 0 && d < best_d) {
        best = k;
        best_d = d;
      }
    }
    *dist = best_d;
    return best;
  }
  // Best first: candidates in a heap by the L1 bound of their distance,
  // filled ring by ring around q's bucket (a target whose region's centre
  // lies in ring r >= 1 is at least (r - 1) cell + 1 - pad_ steps away) while
  // the next ring could hold a better one; a field is read (a cache miss,
  // likely) only while the bound may beat the best.
  const Lattice& lattice = problem_->map->lattice();
  const BucketGrid& g = open_index_;
  const int x = lattice.Ix(q), y = lattice.Iy(q);
  const int bx = x / g.cell(), by = y / g.cell();
  const int rings = g.rings();
  near_.clear();
  int r = 0;
  for (;;) {
    while (r <= rings && (near_.empty() || near_.front().first >=
                                               (r - 1) * g.cell() + 1 - pad_)) {
      g.VisitRing(bx, bx, by, by, r, [&](int k) {
        if (!ok[k]) return;
        const int lb = region_box_[k].Distance(x, y);
        if (best >= 0 && lb > best_d) return;  // never read
        near_.push_back({lb, k});
        std::push_heap(near_.begin(), near_.end(), std::greater<>());
      });
      ++r;
    }
    if (near_.empty()) break;
    std::pop_heap(near_.begin(), near_.end(), std::greater<>());
    const auto [lb, k] = near_.back();
    near_.pop_back();
    if (best >= 0 && lb > best_d) break;
    const int d = static_field_[k][q];
    if (d >= 0 && (best < 0 || d < best_d || (d == best_d && k < best))) {
      best = k;
      best_d = d;
    }
  }
  *dist = best_d;
  return best;
}

int SamplingTree::ReachOf(int k, const int* positions) const {
  const SamplingProblem& p = *problem_;
  const int* field = static_field_[k];
  int reach = std::numeric_limits<int>::max();
  if (!robots_indexed_) {
    for (int i = 0; i < n_; ++i) {
      const int f = p.active[i] ? field[positions[i]] : -1;
      if (f >= 0) reach = std::min(reach, f);
    }
    return reach;
  }
  const LatticeRect& b = region_box_[k];
  if (b.empty()) return reach;  // no region
  const Lattice& lattice = p.map->lattice();
  const BucketGrid& g = robot_index_;
  const int bx0 = b.x0 / g.cell(), bx1 = b.x1 / g.cell();
  const int by0 = b.y0 / g.cell(), by1 = b.y1 / g.cell();
  // A robot in ring r >= 1 around the region's buckets is at least
  // (r - 1) cell + 1 steps away.
  for (int r = 0; r <= g.rings(); ++r) {
    if (r > 0 && (r - 1) * g.cell() + 1 >= reach) break;
    g.VisitRing(bx0, bx1, by0, by1, r, [&](int i) {
      const int q = positions[i];
      if (b.Distance(lattice.Ix(q), lattice.Iy(q)) >= reach) return;
      const int f = field[q];
      if (f >= 0) reach = std::min(reach, f);
    });
  }
  return reach;
}

int SamplingTree::NearestOpen(int q, int depth) {
  int d = 0;
  return NearestTarget(q, depth, open_, &d);
}

}  // namespace aia
