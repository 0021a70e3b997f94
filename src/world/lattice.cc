#include "aia/world/lattice.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "aia/core/check.h"
#include "aia/core/grid.h"

namespace aia {
namespace {

bool DiscFree(const Vec2& c, double r, const Vec2& ws,
              const std::vector<Box>& obstacles) {
  if (c.x() - r < 0.0 || c.y() - r < 0.0 || c.x() + r > ws.x() ||
      c.y() + r > ws.y())
    return false;
  const double r2 = r * r;
  for (const Box& b : obstacles) {
    if (PointBoxDistanceSq(c, b) <= r2) return false;
  }
  return true;
}

bool SweepFree(const Vec2& a, const Vec2& b, double r,
               const std::vector<Box>& obstacles) {
  for (const Box& box : obstacles) {
    if (SegmentBoxDistance(a, b, box) <= r) return false;
  }
  return true;
}

}  // namespace

Lattice::Lattice(const Vec2& workspace, double step, double radius,
                 const std::vector<Box>& obstacles)
    : nx_(static_cast<int>(std::floor(workspace.x() / step + 1e-9))),
      ny_(static_cast<int>(std::floor(workspace.y() / step + 1e-9))),
      step_(step) {
  AIA_CHECK(step > 0.0 && radius >= 0.0);
  static std::atomic<std::uint64_t> built{0};
  id_ = ++built;
  const int n = size();
  free_.assign(n, 0);
  next_.assign(static_cast<size_t>(n) * kNumMoves, -1);
  // Only boxes near a point can touch its disc; bucket them per lattice cell
  // so map-made worlds with hundreds of boxes stay fast.
  std::vector<std::vector<int>> near(n);
  const double reach = radius + step;  // covers the point and its move segments
  for (int b = 0; b < static_cast<int>(obstacles.size()); ++b) {
    const Box& box = obstacles[b];
    const int x0 =
        std::max(0, static_cast<int>(std::floor((box.lo.x() - reach) / step)));
    const int x1 = std::min(
        nx_ - 1, static_cast<int>(std::floor((box.hi.x() + reach) / step)));
    const int y0 =
        std::max(0, static_cast<int>(std::floor((box.lo.y() - reach) / step)));
    const int y1 = std::min(
        ny_ - 1, static_cast<int>(std::floor((box.hi.y() + reach) / step)));
    for (int iy = y0; iy <= y1; ++iy)
      for (int ix = x0; ix <= x1; ++ix) near[Index(ix, iy)].push_back(b);
  }
  std::vector<Box> local;
  auto gather = [&](int idx) {
    local.clear();
    for (int b : near[idx]) local.push_back(obstacles[b]);
  };
  for (int idx = 0; idx < n; ++idx) {
    gather(idx);
    free_[idx] = DiscFree(Point(idx), radius, workspace, local) ? 1 : 0;
    num_free_ += free_[idx];
  }
  for (int idx = 0; idx < n; ++idx) {
    if (!free_[idx]) continue;
    gather(idx);
    for (Move m : kMoves) {
      const auto d = MoveDelta(m);
      const int jx = Ix(idx) + d[0], jy = Iy(idx) + d[1];
      if (jx < 0 || jy < 0 || jx >= nx_ || jy >= ny_) continue;
      const int j = Index(jx, jy);
      if (!free_[j]) continue;
      if (!SweepFree(Point(idx), Point(j), radius, local)) continue;
      next_[static_cast<size_t>(idx) * kNumMoves + static_cast<int>(m)] = j;
    }
  }
  // Components by flood fill, then renumbered largest first.
  component_.assign(n, -1);
  std::vector<int> sizes, stack;
  for (int s = 0; s < n; ++s) {
    if (!free_[s] || component_[s] >= 0) continue;
    const int id = static_cast<int>(sizes.size());
    int count = 0;
    stack.assign(1, s);
    component_[s] = id;
    while (!stack.empty()) {
      const int u = stack.back();
      stack.pop_back();
      ++count;
      for (Move m : kMoves) {
        const int v = Next(u, m);
        if (v >= 0 && component_[v] < 0) {
          component_[v] = id;
          stack.push_back(v);
        }
      }
    }
    sizes.push_back(count);
  }
  num_components_ = static_cast<int>(sizes.size());
  std::vector<int> order(sizes.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return sizes[a] > sizes[b]; });
  std::vector<int> rank(sizes.size());
  for (size_t r = 0; r < order.size(); ++r)
    rank[order[r]] = static_cast<int>(r);
  for (int& c : component_)
    if (c >= 0) c = rank[c];
}

int Lattice::NumValidMoves(int idx) const {
  int count = 0;
  for (Move m : kMoves) count += Valid(idx, m) ? 1 : 0;
  return count;
}

int Lattice::NearestPoint(const Vec2& p) const {
  const int ix = FloorIndex(p.x() / step_, nx_);
  const int iy = FloorIndex(p.y() / step_, ny_);
  return Index(ix, iy);
}

int Lattice::NearestFree(const Vec2& p) const {
  const int c = NearestPoint(p);
  if (free_[c]) return c;
  // Search rings of growing radius; a ring at Chebyshev distance k holds points
  // at least (k - 1) steps away, so stop once that exceeds the best found.
  int best = -1;
  double best_d2 = std::numeric_limits<double>::infinity();
  const int cx = Ix(c), cy = Iy(c);
  const int kmax = std::max(nx_, ny_);
  for (int k = 1; k <= kmax; ++k) {
    const double ring_min = (k - 1) * step_;
    if (best >= 0 && ring_min * ring_min > best_d2) break;
    for (int iy = cy - k; iy <= cy + k; ++iy) {
      for (int ix = cx - k; ix <= cx + k; ++ix) {
        if (std::max(std::abs(ix - cx), std::abs(iy - cy)) != k) continue;
        if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) continue;
        const int idx = Index(ix, iy);
        if (!free_[idx]) continue;
        const double d2 = (Point(idx) - p).squaredNorm();
        if (d2 < best_d2) {
          best_d2 = d2;
          best = idx;
        }
      }
    }
  }
  return best;
}

void BfsDistances(const Lattice& lattice, const int* sources, int num_sources,
                  std::vector<int>* dist, std::vector<int>* queue) {
  dist->assign(lattice.size(), -1);
  queue->resize(lattice.size());
  size_t head = 0, tail = 0;
  for (int s = 0; s < num_sources; ++s) {
    const int src = sources[s];
    if (src < 0 || !lattice.Free(src) || (*dist)[src] == 0) continue;
    (*dist)[src] = 0;
    (*queue)[tail++] = src;
  }
  while (head < tail) {
    const int u = (*queue)[head++];
    const int du = (*dist)[u];
    for (Move m : kMoves) {
      const int v = lattice.Next(u, m);
      if (v >= 0 && (*dist)[v] < 0) {
        (*dist)[v] = du + 1;
        (*queue)[tail++] = v;
      }
    }
  }
}

Move StepDownField(const Lattice& lattice, const std::vector<int>& dist,
                   int from) {
  const int d = dist[from];
  if (d <= 0) return Move::kStay;
  for (Move m : kMoves) {
    const int v = lattice.Next(from, m);
    if (v >= 0 && dist[v] == d - 1) return m;
  }
  return Move::kStay;
}

Move ApplyWorldRule(const Lattice& lattice, int from, Move wanted, Rng& rng,
                    bool* replaced) {
  *replaced = false;
  if (wanted == Move::kStay || lattice.Valid(from, wanted)) return wanted;
  *replaced = true;
  return RandomValidMove(lattice, from, rng);
}

Move MoveBetween(const Lattice& lattice, int a, int b) {
  for (Move m : kMoves)
    if (lattice.Next(a, m) == b) return m;
  return Move::kStay;
}

Move RandomValidMove(const Lattice& lattice, int from, Rng& rng) {
  Move valid[kNumMoves];
  int count = 0;
  for (Move m : kMoves)
    if (lattice.Valid(from, m)) valid[count++] = m;
  return count == 0 ? Move::kStay : valid[rng.UniformInt(count)];
}

}  // namespace aia
