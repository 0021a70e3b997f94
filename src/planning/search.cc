#include "aia/planning/search.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "aia/core/check.h"

namespace aia {
namespace {

// record(i) for each robot i of `robots`, split over `run`'s `workers`
// (each robot's memory is its own); the points added, summed.
template <typename Record>
long RecordAll(const std::vector<int>& robots, const RangeRunner& run,
               int workers, std::vector<long>* added, Record record) {
  added->assign(std::max(1, workers), 0);
  RunRange(run, static_cast<int>(robots.size()), [&](int b0, int b1, int w) {
    for (int b = b0; b < b1; ++b) (*added)[w] += record(robots[b]);
  });
  long sum = 0;
  for (long a : *added) sum += a;
  return sum;
}

// Whether robot i measured target k this step: its own measurements where
// the context has them; else (a hand-made context) whether its belief shrank
// from `before` to `now`. At scale the belief also shrinks as a neighbour's
// measurement spreads through the consensus: that is no measurement of the
// robot's own and must not clear its misses.
bool Measured(const DecisionContext& ctx, int i, int k, double before,
              double now) {
  if (ctx.measurements) {
    for (const Measurement& z : (*ctx.measurements)[i])
      if (z.target == k) return true;
    return false;
  }
  return now < before + std::log1p(-1e-9);
}

// One slot (robot i's target k) of either memory at this step: records its
// belief's log det and mean, and says whether the robot is still searching
// the target (static, open in its belief, not measured since the last call;
// never at the first call).
template <typename Slot>
bool StillSearching(const DecisionContext& ctx, int robot, int k,
                    double log_eps, Slot* s) {
  const double now = LogDetOf(ctx, robot, k);
  const bool first = std::isnan(s->log_det);
  const bool measured = !first && Measured(ctx, robot, k, s->log_det, now);
  s->log_det = now;
  s->mean = MeanOf(ctx, robot, k);
  return !first && !measured && now > log_eps &&
         ctx.beliefs->layout().is_static(k);
}

}  // namespace

int NearestObserverDistance(const Map& map, const SensorModel& sensor, int here,
                            const Vec2& x, int span, int bound) {
  const Lattice& lattice = map.lattice();
  const int c = lattice.NearestPoint(x);
  const int component = lattice.components()[here];
  const int hx = lattice.Ix(here), hy = lattice.Iy(here);
  const int x0 = std::max(0, lattice.Ix(c) - span);
  const int x1 = std::min(lattice.nx() - 1, lattice.Ix(c) + span);
  const int y0 = std::max(0, lattice.Iy(c) - span);
  const int y1 = std::min(lattice.ny() - 1, lattice.Iy(c) + span);
  // The distance from v to [lo, hi], and to its far end.
  const auto near = [](int v, int lo, int hi) {
    return v < lo ? lo - v : v > hi ? v - hi : 0;
  };
  const auto far = [](int v, int lo, int hi) {
    return std::max(std::abs(v - lo), std::abs(v - hi));
  };
  const int d_lo = near(hx, x0, x1) + near(hy, y0, y1);
  const int d_hi = far(hx, x0, x1) + far(hy, y0, y1);
  for (int d = d_lo; d <= d_hi; ++d) {
    if (d >= bound) return bound;
    for (int ix = x0; ix <= x1; ++ix) {
      const int rest = d - std::abs(ix - hx);
      if (rest < 0) continue;
      for (const int iy : {hy - rest, hy + rest}) {
        if (iy >= y0 && iy <= y1) {
          const int q = lattice.Index(ix, iy);
          if (lattice.Free(q) && lattice.components()[q] == component &&
              PredictedPrecision(map, sensor, lattice.Point(q), x) > 0.0)
            return d;
        }
        if (rest == 0) break;  // one point, not two
      }
    }
  }
  return -1;
}

// --- MissSlots ---------------------------------------------------------------

template <typename Derived, typename Slot, typename Shared>
void MissSlots<Derived, Slot, Shared>::Reset(int num_robots, int num_targets) {
  AIA_CHECK(num_robots >= 0 && num_targets >= 0);
  num_robots_ = num_robots;
  num_targets_ = num_targets;
  slots_.assign(static_cast<std::size_t>(num_robots) * num_targets, Slot{});
  touched_.assign(num_robots, 1);
  misses_ = 0;
  derived().Resized();
}

template <typename Derived, typename Slot, typename Shared>
int MissSlots<Derived, Slot, Shared>::Record(const DecisionContext& ctx,
                                             int robot) {
  AIA_CHECK(robot >= 0 && robot < num_robots_);
  AIA_CHECK(ctx.beliefs->layout().num_targets() == num_targets_);
  touched_[robot] = 1;  // (each robot's byte is its own thread's)
  const Map& map = *ctx.map;
  const int here = (*ctx.robot_lattice)[robot];
  const Vec2 p = map.lattice().Point(here);
  const double log_eps = std::log(ctx.eps);
  int added = 0;
  for (int k = 0; k < num_targets_; ++k) {
    Slot& s = slot(robot, k);
    const bool searching = StillSearching(ctx, robot, k, log_eps, &s);
    derived().Settle(static_cast<std::size_t>(robot) * num_targets_ + k, &s,
                     searching);
    if (!searching) continue;
    if (s.missed.empty()) derived().Unmissed(ctx, robot, k);
    // Nothing measured, though this point sees where the target was looked
    // for: it is not anywhere the point would have measured.
    if (!Derived::Sees(map, *ctx.sensor, p, s) ||
        std::find(s.missed.begin(), s.missed.end(), here) != s.missed.end())
      continue;
    s.missed.push_back(here);
    ++added;
    derived().Recompute(ctx, robot, k);
  }
  return added;
}

template <typename Derived, typename Slot, typename Shared>
void MissSlots<Derived, Slot, Shared>::Update(const DecisionContext& ctx,
                                              int robot) {
  derived().Prepare(ctx);
  misses_ += Record(ctx, robot);
}

template <typename Derived, typename Slot, typename Shared>
void MissSlots<Derived, Slot, Shared>::Update(const DecisionContext& ctx,
                                              const std::vector<int>& robots,
                                              const RangeRunner& run,
                                              int workers) {
  derived().Prepare(ctx);
  misses_ += RecordAll(robots, run, workers, &added_,
                       [&](int i) { return Record(ctx, i); });
}

template <typename Derived, typename Slot, typename Shared>
void MissSlots<Derived, Slot, Shared>::Share(const DecisionContext& ctx,
                                             const std::vector<int>& robots,
                                             const RangeRunner& run,
                                             int workers) {
  if (static_cast<int>(caches_.size()) < std::max(1, workers))
    caches_.resize(std::max(1, workers));
  for (Cache& cache : caches_) cache.Clear();
  sharing_.Share(
      ctx, robots, num_targets_, &slots_,
      [&](int i, int k, int group, int worker) {
        derived().RecomputeShared(ctx, i, k, group, &caches_[worker]);
      },
      &touched_, run, workers);
}

template class MissSlots<SearchMemory, internal::AimSlot, internal::SharedWalk>;
template class MissSlots<SearchPoints, internal::PointsSlot,
                         internal::SharedPoints>;

// --- SearchMemory ------------------------------------------------------------

bool SearchMemory::Reaim(const DecisionContext& ctx, int robot, int k) {
  const Map& map = *ctx.map;
  const SensorModel& sensor = *ctx.sensor;
  const Lattice& lattice = map.lattice();
  const int here = (*ctx.robot_lattice)[robot];
  const int span = SensorSpan(lattice, sensor);
  // Near: the lattice distance (|dx| + |dy|) from the robot to the nearest
  // point of its own component that would measure a target at x.
  const auto cost = [&](const Vec2& x, int bound) {
    return NearestObserverDistance(map, sensor, here, x, span, bound);
  };
  auto& s = slot(robot, k);
  const Mat2 cov = ctx.beliefs->PositionCovariance(robot, k);
  if (SearchAim(map, sensor, s.mean, cov, &s.missed.points(), cost, &s.aim))
    return true;
  // The prior is searched to 4 sigma: forget, and search it again.
  s.missed.clear();
  s.aim = s.mean;
  start_[static_cast<std::size_t>(robot) * num_targets_ + k] = kUnchecked;
  return false;
}

void SearchMemory::Settle(std::size_t at, internal::AimSlot* s,
                          bool searching) {
  if (!searching) {
    s->missed.clear();
    start_[at] = kUnchecked;
  }
  if (s->missed.empty() && start_[at] != kRing) s->aim = s->mean;
}

void SearchMemory::Prepare(const DecisionContext& ctx) {
  const Lattice& lattice = ctx.map->lattice();
  if (clear_for_ == lattice.id() && !clear_.empty()) return;
  const Grid<std::uint8_t>& occupancy = ctx.map->occupancy();
  const double half = 0.5 * lattice.step();
  clear_.assign(static_cast<std::size_t>(lattice.size()), 0);
  for (int q = 0; q < lattice.size(); ++q) {
    if (!lattice.Free(q)) continue;
    const Vec2 p = lattice.Point(q);
    int x0, y0, x1, y1;
    occupancy.CellOf(p - Vec2(half, half), &x0, &y0);
    occupancy.CellOf(p + Vec2(half, half), &x1, &y1);
    bool clear = true;
    for (int iy = y0; clear && iy <= y1; ++iy)
      for (int ix = x0; clear && ix <= x1; ++ix) clear = occupancy(ix, iy) == 0;
    clear_[q] = clear ? 1 : 0;
  }
  clear_for_ = lattice.id();
}

void SearchMemory::Unmissed(const DecisionContext& ctx, int robot, int k) {
  std::uint8_t& start =
      start_[static_cast<std::size_t>(robot) * num_targets_ + k];
  if (start != kUnchecked) return;
  // Once a search starts (the mean it has then: a static target's moves
  // only by the consensus until measured, which ends the search), and the
  // window scanned only for a mean in an obstacle or whose nearest lattice
  // point is not a free one of the robot's component or does not see it (a
  // scan of every slot's window would cost seconds a step at 1000 x 1000).
  const auto& s = slot(robot, k);
  const Lattice& lattice = ctx.map->lattice();
  const int here = (*ctx.robot_lattice)[robot];
  const int component = lattice.components()[here];
  const int nearest = lattice.NearestPoint(s.mean);
  const Vec2 p = lattice.Point(nearest);
  const Vec2 off = (s.mean - p).cwiseAbs();
  const double half = 0.5 * lattice.step();
  // Seen from its nearest point: cheaply where the point's half-step square
  // holds the mean and no obstacle, else by the line of sight.
  const bool seen =
      lattice.Free(nearest) && lattice.components()[nearest] == component &&
      ((clear_[nearest] && off.x() <= half && off.y() <= half &&
        ctx.sensor->InRange(off.norm())) ||
       (ctx.map->PointFree(s.mean) &&
        PredictedPrecision(*ctx.map, *ctx.sensor, p, s.mean) > 0.0));
  const bool suspect = !seen;
  const bool ring =
      suspect &&
      NearestObserverDistance(*ctx.map, *ctx.sensor, here, s.mean,
                              SensorSpan(lattice, *ctx.sensor)) < 0 &&
      Reaim(ctx, robot, k);
  start = ring ? kRing : kMean;
}

bool SearchMemory::Sees(const Map& map, const SensorModel& sensor,
                        const Vec2& p, const internal::AimSlot& s) {
  return PredictedPrecision(map, sensor, p, s.aim) > 0.0;
}

bool SearchMemory::RecomputeShared(const DecisionContext& ctx, int robot, int k,
                                   int group, Cache* cache) {
  const Map& map = *ctx.map;
  const SensorModel& sensor = *ctx.sensor;
  const Lattice& lattice = map.lattice();
  const int span = SensorSpan(lattice, sensor);
  auto& s = slot(robot, k);
  const Mat2 cov = ctx.beliefs->PositionCovariance(robot, k);
  bool made = false;
  internal::SharedWalk& walk = cache->Find(
      group, k,
      [&](const internal::SharedWalk& w) {
        return w.mean == s.mean && w.cov == cov;
      },
      &made);
  if (made) {
    walk.mean = s.mean;
    walk.cov = cov;
    walk.ring_end.clear();
    walk.points.clear();
  }
  const int here = (*ctx.robot_lattice)[robot];
  const int component = lattice.components()[here];
  const int hx = lattice.Ix(here), hy = lattice.Iy(here);
  // NearestObserverDistance from the point's summary: where the robot lies
  // beyond a corner of the observers' box, every observer is nearer along
  // both axes the same way, and the corner sum gives the least distance.
  const auto cost = [&](const internal::SharedWalk::RingPoint& p, int bound) {
    if (p.component == -1) return -1;
    if (p.component >= 0 && p.component != component) return -1;
    if (p.component >= 0) {
      if (hx <= p.x0 && hy <= p.y0) return p.corner[0] - hx - hy;
      if (hx >= p.x1 && hy <= p.y0) return p.corner[1] + hx - hy;
      if (hx <= p.x0 && hy >= p.y1) return p.corner[2] - hx + hy;
      if (hx >= p.x1 && hy >= p.y1) return p.corner[3] + hx + hy;
    }
    return NearestObserverDistance(map, sensor, here, p.x, span, bound);
  };
  int best = std::numeric_limits<int>::max();
  for (int r = 0; r <= PriorRings::kLast; ++r) {
    if (r == static_cast<int>(walk.ring_end.size())) {
      // Ring r's candidates: free, and not ruled out by the missed points
      // (the neighbourhood's union, which this robot now holds).
      const std::vector<Vec2>& ruled =
          MissedPoints(lattice, &s.missed.points());
      PriorRings(walk.mean, walk.cov, lattice.step())
          .Visit(r, [&](const Vec2& x) {
            if (!map.PointFree(x) || RuledOut(map, sensor, ruled, x)) return;
            internal::SharedWalk::RingPoint p;
            p.x = x;
            ForEachInWindow(lattice, lattice.NearestPoint(x), span,
                            [&](int q, int ix, int iy) {
                              if (!lattice.Free(q) ||
                                  PredictedPrecision(
                                      map, sensor, lattice.Point(q), x) <= 0.0)
                                return;
                              const std::array<int, 4> sums = {
                                  ix + iy, -ix + iy, ix - iy, -ix - iy};
                              if (p.component == -1) {
                                p.component = lattice.components()[q];
                                p.x0 = p.x1 = ix;
                                p.y0 = p.y1 = iy;
                                p.corner = sums;
                                return;
                              }
                              if (p.component != lattice.components()[q])
                                p.component = -2;
                              p.x0 = std::min(p.x0, ix);
                              p.x1 = std::max(p.x1, ix);
                              p.y0 = std::min(p.y0, iy);
                              p.y1 = std::max(p.y1, iy);
                              for (int e = 0; e < 4; ++e)
                                p.corner[e] = std::min(p.corner[e], sums[e]);
                            });
            walk.points.push_back(p);
          });
      walk.ring_end.push_back(static_cast<int>(walk.points.size()));
    }
    for (int a = r == 0 ? 0 : walk.ring_end[r - 1]; a < walk.ring_end[r]; ++a) {
      const int c = cost(walk.points[a], best);
      if (c < 0 || c >= best) continue;
      best = c;
      s.aim = walk.points[a].x;
    }
    if (best != std::numeric_limits<int>::max()) return true;
  }
  // The prior is searched to 4 sigma: forget, and search it again (its
  // start checked again, as Reaim's forget does: a mean no point sees kept
  // its ring mark, and the aim stayed at the unseen mean for good).
  s.missed.clear();
  s.aim = s.mean;
  start_[static_cast<std::size_t>(robot) * num_targets_ + k] = kUnchecked;
  return false;
}

void SearchPoints::Recompute(const DecisionContext& ctx, int robot, int k) {
  const Map& map = *ctx.map;
  const SensorModel& sensor = *ctx.sensor;
  const Lattice& lattice = map.lattice();
  const int here = (*ctx.robot_lattice)[robot];
  const int span = SensorSpan(lattice, sensor);
  // Some free point of the robot's component would measure a target at x.
  const auto observable = [&](const Vec2& x) {
    return NearestObserverDistance(map, sensor, here, x, span) >= 0;
  };
  auto& s = slot(robot, k);
  const Mat2 cov = ctx.beliefs->PositionCovariance(robot, k);
  const std::vector<Vec2>& ruled = MissedPoints(lattice, &s.missed.points());
  s.points.clear();
  bool mean_viable = false;
  int index = 0;
  const int ring = WalkPriorRings(
      s.mean, cov, lattice.step(),
      [&](const Vec2& x) {
        const bool first = index++ == 0;
        if (!map.PointFree(x) || RuledOut(map, sensor, ruled, x) ||
            !observable(x))
          return;
        if (first) mean_viable = true;
        s.points.push_back(x);
      },
      [&] { return !s.points.empty(); });
  if (ring < 0) {  // searched to 4 sigma: forget, and search it again
    s.missed.clear();
    s.points.clear();
  } else if (mean_viable) {
    s.points.clear();  // the mean itself
  }
}

void SearchPoints::Settle(std::size_t, internal::PointsSlot* s,
                          bool searching) {
  if (searching) return;
  s->missed.clear();
  s->points.clear();
}

bool SearchPoints::Sees(const Map& map, const SensorModel& sensor,
                        const Vec2& p, const internal::PointsSlot& s) {
  if (s.points.empty()) return PredictedPrecision(map, sensor, p, s.mean) > 0.0;
  for (const Vec2& x : s.points)
    if (PredictedPrecision(map, sensor, p, x) > 0.0) return true;
  return false;
}

void SearchPoints::RecomputeShared(const DecisionContext& ctx, int robot, int k,
                                   int group, Cache* cache) {
  auto& s = slot(robot, k);
  const Mat2 cov = ctx.beliefs->PositionCovariance(robot, k);
  const int component =
      ctx.map->lattice().components()[(*ctx.robot_lattice)[robot]];
  bool made = false;
  internal::SharedPoints& e = cache->Find(
      group, k,
      [&](const internal::SharedPoints& p) {
        return p.mean == s.mean && p.cov == cov && p.component == component;
      },
      &made);
  if (!made) {
    if (e.forgot) s.missed.clear();
    s.points = e.points;
    return;
  }
  Recompute(ctx, robot, k);
  e.mean = s.mean;
  e.cov = cov;
  e.component = component;
  e.forgot = s.missed.empty();  // it held the union's points before
  e.points = s.points;
}

Move TowardNearestAim::FirstMove(const Map& map, const SensorModel& sensor,
                                 int p, const std::vector<Vec2>& aims,
                                 const std::vector<std::uint8_t>& open,
                                 int* target) {
  AIA_CHECK(aims.size() == open.size());
  if (target) *target = -1;
  const Lattice& lattice = map.lattice();
  // The open aims by the lattice point nearest them; their observation points
  // are the points of the (2 span + 1)^2 window around it from which the aim
  // is seen.
  const int span = SensorSpan(lattice, sensor);
  const int num_aims = static_cast<int>(aims.size());
  centres_.resize(num_aims);
  open_.assign(num_aims, 0);
  bool any_open = false;
  for (int k = 0; k < num_aims; ++k) {
    if (!open[k]) continue;
    const int c = lattice.NearestPoint(aims[k]);
    centres_[k] = Vec2(lattice.Ix(c), lattice.Iy(c));
    open_[k] = 1;
    any_open = true;
  }
  if (!any_open) return Move::kStay;
  const double radius = 1.5 * span;  // covers the window's corners
  open_index_.Build(centres_, radius, &open_);

  // BFS from the robot, remembering each point's first move, popped in order
  // of distance. The first distance that holds an observation point decides;
  // among its points the one of the lowest target, then the lowest point
  // index (row by row), which is what scanning every target's window over a
  // full BFS in that order finds, at the cost of the BFS out to that distance.
  const int n = lattice.size();
  if (static_cast<int>(dist_.size()) != n) {
    dist_.assign(n, -1);
    first_.assign(n, Move::kStay);
    queue_.resize(n);
  }
  size_t head = 0, tail = 0;
  dist_[p] = 0;
  queue_[tail++] = p;
  int best_k = -1, best_q = -1, best_dist = 0;
  while (head < tail) {
    const int u = queue_[head++];
    const int d = dist_[u];
    if (best_k >= 0 && d > best_dist) break;
    if (d >= 1) {
      const int ux = lattice.Ix(u), uy = lattice.Iy(u);
      near_.clear();
      open_index_.Near(centres_, Vec2(ux, uy), radius, &near_);
      for (int k : near_) {  // ascending
        if (best_k >= 0 && (k > best_k || (k == best_k && u > best_q))) break;
        if (std::abs(static_cast<int>(centres_[k].x()) - ux) > span ||
            std::abs(static_cast<int>(centres_[k].y()) - uy) > span)
          continue;
        if (PredictedPrecision(map, sensor, lattice.Point(u), aims[k]) <= 0.0)
          continue;
        best_k = k;
        best_q = u;
        best_dist = d;
        break;
      }
    }
    if (best_k >= 0) continue;  // the rest of this distance only
    for (Move m : kMoves) {
      const int v = lattice.Next(u, m);
      if (v < 0 || dist_[v] >= 0) continue;
      dist_[v] = d + 1;
      first_[v] = (u == p) ? m : first_[u];
      queue_[tail++] = v;
    }
  }
  const Move move = best_k < 0 ? Move::kStay : first_[best_q];
  for (size_t i = 0; i < tail; ++i) dist_[queue_[i]] = -1;
  if (target) *target = move == Move::kStay ? -1 : best_k;
  return move;
}

void TargetClaims::Reset() {
  index_.clear();
  by_sources_.clear();
  free_.clear();
  fields_.clear();
  used_ = 0;
  map_ = nullptr;
  sensor_ = nullptr;
}

int TargetClaims::Horizon(int num_targets, const Lattice& lattice, int span) {
  const long points = lattice.size();
  if (num_targets <= 0 || num_targets * points <= kFieldBudget) return -1;
  const double side =
      std::sqrt(static_cast<double>(kFieldBudget) / num_targets);
  const int moves = static_cast<int>((side - 1.0) / 2.0) - span;
  return std::max(moves, 2 * span);
}

void TargetClaims::Begin(const Map& map, const SensorModel& sensor,
                         int num_targets) {
  const Lattice& lattice = map.lattice();
  const int span = SensorSpan(lattice, sensor);
  const int horizon = Horizon(num_targets, lattice, span);
  span_ = span;
  if (map_ != &map || sensor_ != &sensor ||
      (sensor_ && sensor_->range != range_) || horizon != horizon_) {
    Reset();
  } else {
    // Keep the fields the last step used (most aims do not move between
    // steps); free the others.
    for (auto it = index_.begin(); it != index_.end();) {
      if (it->second.step.load(std::memory_order_relaxed) != step_) {
        it = index_.erase(it);
      } else {
        ++it;
      }
    }
    for (int slot = 0; slot < static_cast<int>(fields_.size()); ++slot) {
      std::unique_ptr<AimField>& field = fields_[slot];
      if (!field || field->step.load(std::memory_order_relaxed) == step_)
        continue;
      by_sources_.erase(field->sources());
      field.reset();
      free_.push_back(slot);
    }
  }
  map_ = &map;
  sensor_ = &sensor;
  range_ = sensor.range;
  horizon_ = horizon;
  ++step_;
  used_ = 0;
}

void TargetClaims::AimField::Compute(const Lattice& lattice,
                                     const std::vector<int>& sources,
                                     int horizon, std::vector<int>* queue) {
  sources_ = sources;
  whole_ = horizon < 0;
  if (whole_) {
    x0_ = y0_ = 0;
    nx_ = lattice.nx();
    ny_ = lattice.ny();
    BfsDistances(lattice, sources.data(), static_cast<int>(sources.size()),
                 &dist_, queue);
    return;
  }
  // A point within `horizon` moves of a source lies in the sources' box
  // grown by `horizon`: the window, so that a move from a point nearer
  // than the horizon never leaves it.
  int x_lo = lattice.nx(), y_lo = lattice.ny(), x_hi = -1, y_hi = -1;
  for (int q : sources) {
    x_lo = std::min(x_lo, lattice.Ix(q));
    x_hi = std::max(x_hi, lattice.Ix(q));
    y_lo = std::min(y_lo, lattice.Iy(q));
    y_hi = std::max(y_hi, lattice.Iy(q));
  }
  if (x_hi < 0) {  // no source: nothing is in reach
    x0_ = y0_ = nx_ = ny_ = 0;
    dist_.clear();
    return;
  }
  x0_ = std::max(0, x_lo - horizon);
  y0_ = std::max(0, y_lo - horizon);
  nx_ = std::min(lattice.nx() - 1, x_hi + horizon) - x0_ + 1;
  ny_ = std::min(lattice.ny() - 1, y_hi + horizon) - y0_ + 1;
  dist_.assign(static_cast<std::size_t>(nx_) * ny_, -1);
  const auto local = [&](int q) {
    return (lattice.Iy(q) - y0_) * nx_ + (lattice.Ix(q) - x0_);
  };
  // The local offset of each move of kMoves (left, right, up, down; y up).
  const std::array<int, kNumMoves> offset = {-1, 1, nx_, -nx_};
  // (point, local index) pairs.
  queue->resize(2 * dist_.size());
  std::size_t head = 0, tail = 0;
  for (int q : sources) {
    const int l = local(q);
    if (!lattice.Free(q) || dist_[l] == 0) continue;
    dist_[l] = 0;
    (*queue)[tail++] = q;
    (*queue)[tail++] = l;
  }
  while (head < tail) {
    const int u = (*queue)[head++], lu = (*queue)[head++];
    const int du = dist_[lu];
    if (du >= horizon) continue;
    for (int a = 0; a < kNumMoves; ++a) {
      const int v = lattice.Next(u, kMoves[a]);
      if (v < 0) continue;
      const int lv = lu + offset[a];
      if (dist_[lv] >= 0) continue;
      dist_[lv] = du + 1;
      (*queue)[tail++] = v;
      (*queue)[tail++] = lv;
    }
  }
}

Move TargetClaims::AimField::StepDown(const Lattice& lattice, int p) const {
  const int d = At(lattice, p);
  if (d <= 0) return Move::kStay;
  for (Move m : kMoves) {
    const int v = lattice.Next(p, m);
    if (v >= 0 && At(lattice, v) == d - 1) return m;
  }
  return Move::kStay;
}

const TargetClaims::AimField& TargetClaims::Field(const Vec2& aim) {
  AIA_CHECK_MSG(map_ && sensor_, "Begin() before Field()");
  const PointKey key = KeyOf(aim);
  const auto used = [&](int slot) -> const AimField& {
    fields_[slot]->step.store(step_, std::memory_order_relaxed);
    return *fields_[slot];
  };
  {
    std::shared_lock<std::shared_mutex> lock(fields_mutex_);
    const auto it = index_.find(key);
    if (it != index_.end()) {
      it->second.step.store(step_, std::memory_order_relaxed);
      return used(it->second.slot);
    }
  }
  // The aim's points, then its field if no other aim has them; made
  // outside the lock (another thread may make the same field: the first
  // one kept, the same either way).
  thread_local std::vector<int> sources, queue;
  const Lattice& lattice = map_->lattice();
  const int span = SensorSpan(lattice, *sensor_);
  sources.clear();
  ForEachInWindow(
      lattice, lattice.NearestPoint(aim), span, [&](int q, int, int) {
        if (lattice.Free(q) &&
            PredictedPrecision(*map_, *sensor_, lattice.Point(q), aim) > 0.0)
          sources.push_back(q);
      });
  // Under the exclusive lock: the aim's entry, pointing at `slot`.
  const auto enter = [&](int slot) -> const AimField& {
    auto [it, fresh] = index_.try_emplace(key);
    if (fresh) it->second.slot = slot;
    it->second.step.store(step_, std::memory_order_relaxed);
    return used(it->second.slot);
  };
  {
    std::unique_lock<std::shared_mutex> lock(fields_mutex_);
    const auto it = by_sources_.find(sources);
    if (it != by_sources_.end()) return enter(it->second);
  }
  auto field = std::make_unique<AimField>();
  field->Compute(lattice, sources, horizon_, &queue);
  std::unique_lock<std::shared_mutex> lock(fields_mutex_);
  const auto [it, fresh] = by_sources_.try_emplace(sources, -1);
  if (fresh) {
    if (free_.empty()) {
      free_.push_back(static_cast<int>(fields_.size()));
      fields_.emplace_back();
    }
    it->second = free_.back();
    free_.pop_back();
    fields_[it->second] = std::move(field);
  }
  return enter(it->second);
}

int TargetClaims::Distance(const Vec2& aim, int p) {
  return Field(aim).At(map_->lattice(), p);
}

bool TargetClaims::ByPosition(int a, int b) const {
  const Lattice& lattice = map_->lattice();
  const Vec2 pa = lattice.Point(a), pb = lattice.Point(b);
  return pa.x() < pb.x() || (pa.x() == pb.x() && pa.y() < pb.y());
}

TargetClaims::Plan& TargetClaims::PlanFor(int self,
                                          const std::vector<int>& others,
                                          const std::vector<Vec2>& aims,
                                          const std::vector<std::uint8_t>& open,
                                          int* at) {
  AIA_CHECK_MSG(map_ && sensor_, "Begin() before Claim() or Route()");
  AIA_CHECK(aims.size() == open.size());
  const int m = static_cast<int>(aims.size());
  const Lattice& lattice = map_->lattice();
  points_.assign(others.begin(), others.end());
  points_.push_back(self);
  const auto before = [this](int a, int b) { return ByPosition(a, b); };
  std::sort(points_.begin(), points_.end(), before);
  *at = static_cast<int>(
      std::lower_bound(points_.begin(), points_.end(), self, before) -
      points_.begin());
  const auto same = [&](const Plan& plan) {
    if (plan.points != points_ || plan.open != open) return false;
    for (int k = 0; k < m; ++k)
      if (open[k] &&
          (plan.aims[k].x() != aims[k].x() || plan.aims[k].y() != aims[k].y()))
        return false;
    return true;
  };
  for (int p = 0; p < used_; ++p)
    if (same(plans_[p])) return plans_[p];
  if (used_ == static_cast<int>(plans_.size())) plans_.emplace_back();
  Plan& plan = plans_[used_++];
  plan.points = points_;
  plan.open = open;
  plan.aims = aims;
  plan.routed = false;
  plan.order.clear();
  // Each open target's owner: the robot nearest to where it can be
  // measured (ties to the first in the points' order: lower x, then y).
  const int n = static_cast<int>(points_.size());
  plan.owner.assign(m, -1);
  plan.helper.assign(m, -1);
  held_.assign(n, 0);
  for (int k = 0; k < m; ++k) {
    if (!open[k]) continue;
    const AimField& f = Field(aims[k]);
    int best = -1, best_d = -1;
    for (int r = 0; r < n; ++r) {
      const int d = f.At(lattice, points_[r]);
      if (d >= 0 && (best < 0 || d < best_d)) {
        best = r;
        best_d = d;
      }
    }
    plan.owner[k] = best;
    if (best >= 0) ++held_[best];
  }
  // Owners of two or more: each such target's helper is the nearest robot
  // that owns none.
  for (int k = 0; k < m; ++k) {
    if (plan.owner[k] < 0 || held_[plan.owner[k]] < 2) continue;
    const AimField& f = Field(aims[k]);
    int best = -1, best_d = -1;
    for (int r = 0; r < n; ++r) {
      if (held_[r] != 0) continue;
      const int d = f.At(lattice, points_[r]);
      if (d >= 0 && (best < 0 || d < best_d)) {
        best = r;
        best_d = d;
      }
    }
    plan.helper[k] = best;
  }
  return plan;
}

void TargetClaims::Claim(int self, const std::vector<int>& others,
                         const std::vector<Vec2>& aims,
                         const std::vector<std::uint8_t>& open,
                         std::vector<std::uint8_t>* mine) {
  AIA_CHECK_MSG(map_ && sensor_, "Begin() before Claim()");
  AIA_CHECK(aims.size() == open.size());
  const int m = static_cast<int>(aims.size());
  const Lattice& lattice = map_->lattice();
  // Robot at point a, da moves away, comes before robot at b, db away.
  const auto before = [this](int a, int da, int b, int db) {
    return da != db ? da < db : ByPosition(a, b);
  };
  mine->assign(m, 0);
  bool any = false;
  const int sx = lattice.Ix(self), sy = lattice.Iy(self);
  for (int k = 0; k < m; ++k) {
    if (!open[k]) continue;
    if (horizon_ >= 0) {
      // The field's sources lie within span_ of the aim's nearest point
      // on each axis: a robot more than the horizon beyond is out of
      // reach, without the field.
      const int c = lattice.NearestPoint(aims[k]);
      if (std::abs(lattice.Ix(c) - sx) + std::abs(lattice.Iy(c) - sy) -
              2 * span_ >
          horizon_)
        continue;
    }
    const AimField& f = Field(aims[k]);
    const int d = f.At(lattice, self);
    if (d < 0) continue;
    bool won = true;
    for (int q : others) {
      const int dq = f.At(lattice, q);
      if (dq >= 0 && before(q, dq, self, d)) {
        won = false;
        break;
      }
    }
    (*mine)[k] = won;
    any = any || won;
  }
  if (any) return;
  const long num_open = std::count(open.begin(), open.end(), 1);
  if (num_open * (static_cast<long>(others.size()) + 1) > kHelpMaxPairs) return;
  // Idle: the targets of owners of two or more where self is the nearest
  // robot that owns none (the team's owners, as every robot works them out).
  std::lock_guard<std::mutex> lock(plans_mutex_);
  int at = 0;
  const Plan& plan = PlanFor(self, others, aims, open, &at);
  for (int k = 0; k < m; ++k) (*mine)[k] = plan.helper[k] == at;
}

class TargetClaims::Legs : public LegOracle {
 public:
  Legs(TargetClaims* claims, const std::vector<Vec2>* aims)
      : claims_(claims), aims_(aims) {}
  Leg Compute(int from, int, int k) override {
    const AimField& f = claims_->Field((*aims_)[k]);
    const Lattice& lattice = claims_->map_->lattice();
    Leg leg;
    leg.steps = f.At(lattice, from);
    if (leg.steps < 0) return leg;
    int q = from;
    while (f.At(lattice, q) > 0) q = lattice.Next(q, f.StepDown(lattice, q));
    leg.end = q;
    return leg;
  }
  int Distance(int from, int k) override {
    return claims_->Field((*aims_)[k]).At(claims_->map_->lattice(), from);
  }
  bool TimeVarying(int) const override { return false; }

 private:
  TargetClaims* claims_;
  const std::vector<Vec2>* aims_;
};

void TargetClaims::Route(int self, const std::vector<int>& others,
                         const std::vector<Vec2>& aims,
                         const std::vector<std::uint8_t>& open,
                         std::vector<std::uint8_t>* mine) {
  const long num_open = std::count(open.begin(), open.end(), 1);
  if (!Plans(num_open, static_cast<long>(others.size()))) {
    Claim(self, others, aims, open, mine);
    return;
  }
  std::lock_guard<std::mutex> lock(plans_mutex_);
  int at = 0;
  Plan& plan = PlanFor(self, others, aims, open, &at);
  const int m = static_cast<int>(aims.size());
  if (!plan.routed) {
    targets_.clear();
    for (int k = 0; k < m; ++k)
      if (open[k]) targets_.push_back(k);
    Legs legs(this, &plan.aims);
    TourSettings settings;
    settings.objective = TourObjective::kMakespan;
    settings.budget = kRouteBudget;
    weight_.assign(m, 1.0);
    plan.order =
        planner_.Plan(plan.points, targets_, weight_, settings, legs).order;
    plan.routed = true;
  }
  mine->assign(m, 0);
  const std::vector<int>& route = plan.order[at];
  if (!route.empty()) (*mine)[route.front()] = 1;
}

// --- ClosedNeighbourhoods ----------------------------------------------------

int ClosedNeighbourhoods::Of(const DecisionContext& ctx, int i, bool* fresh) {
  const std::uint64_t stamp = ctx.comm->graph_stamp();
  const auto n = static_cast<std::size_t>(ctx.comm->size());
  // A new graph (or one without a stamp, at a step's first call) starts
  // the classes again; within a step the graph stays.
  if (stamp != stamp_ || class_of_.size() != n ||
      (stamp == 0 && first_.empty())) {
    AIA_CHECK_MSG(first_.empty(), "the graph changed within a step");
    stamp_ = stamp;
    class_of_.assign(n, -1);
    class_first_.clear();
    class_next_.clear();
    index_.clear();
    group_of_class_.clear();
    group_classes_.clear();
  }
  int c = class_of_[i];
  if (c < 0) {
    std::uint64_t hash = 1469598103934665603ull;  // FNV-1a over the robots
    ForClosed(ctx, i, [&](int j) {
      hash = (hash ^ static_cast<std::uint64_t>(j)) * 1099511628211ull;
    });
    auto it = index_.emplace(hash, -1).first;
    int* link = &it->second;
    for (; *link >= 0; link = &class_next_[*link])
      if (SameClosed(ctx, class_first_[*link], i)) {
        c = *link;
        break;
      }
    if (c < 0) {
      c = *link = static_cast<int>(class_first_.size());
      class_first_.push_back(i);
      class_next_.push_back(-1);
      group_of_class_.push_back(-1);
    }
    class_of_[i] = c;
  }
  int& group = group_of_class_[c];
  *fresh = group < 0;
  if (group < 0) {
    group = static_cast<int>(first_.size());
    first_.push_back(i);
    group_classes_.push_back(c);
  }
  return group;
}

bool ClosedNeighbourhoods::SameClosed(const DecisionContext& ctx, int a,
                                      int b) {
  if (ctx.comm->Neighbors(a).size() != ctx.comm->Neighbors(b).size())
    return false;
  closed_a_.clear();
  ForClosed(ctx, a, [this](int j) { closed_a_.push_back(j); });
  std::size_t n = 0;
  bool same = true;
  ForClosed(ctx, b, [&](int j) {
    same = same && n < closed_a_.size() && closed_a_[n] == j;
    ++n;
  });
  return same && n == closed_a_.size();
}

// --- NeighbourhoodHolds ------------------------------------------------------

void NeighbourhoodHolds::Compute(const DecisionContext& ctx,
                                 const std::vector<int>& robots, double refresh,
                                 const RangeRunner& run) {
  AIA_CHECK(refresh > 0.0 && refresh <= 1.0);
  const int n = static_cast<int>(ctx.robot_lattice->size());
  m_ = ctx.beliefs->layout().num_targets();
  group_of_.assign(n, -1);
  hoods_.Clear();
  for (int i : robots) {
    bool fresh = false;
    group_of_[i] = hoods_.Of(ctx, i, &fresh);
  }
  const int groups = hoods_.size();
  const auto cells = static_cast<std::size_t>(groups) * m_;
  best_.assign(cells, std::numeric_limits<double>::infinity());
  pooled_.assign(cells, std::numeric_limits<double>::infinity());
  open_.assign(cells, 1);
  const double log_eps = std::log(ctx.eps);
  const double log_fresh = log_eps + std::log(refresh);
  // The targets split over `run`; per group, its robots in turn, targets
  // innermost (the digest's rows are per robot). Pooled: the smallest log
  // det first, so that every exp below is at most 1.
  RunRange(run, m_, [&](int k0, int k1, int) {
    for (int g = 0; g < groups; ++g) {
      double* best = best_.data() + static_cast<std::size_t>(g) * m_;
      double* pooled = pooled_.data() + static_cast<std::size_t>(g) * m_;
      int count = 0;
      ClosedNeighbourhoods::ForClosed(ctx, hoods_.robot(g), [&](int j) {
        ++count;
        for (int k = k0; k < k1; ++k)
          best[k] = std::min(best[k], LogDetOf(ctx, j, k));
      });
      for (int k = k0; k < k1; ++k) pooled[k] = 0.0;
      ClosedNeighbourhoods::ForClosed(ctx, hoods_.robot(g), [&](int j) {
        for (int k = k0; k < k1; ++k)
          pooled[k] += std::exp(-0.5 * (LogDetOf(ctx, j, k) - best[k]));
      });
      std::uint8_t* open = open_.data() + static_cast<std::size_t>(g) * m_;
      for (int k = k0; k < k1; ++k) {
        if (std::isfinite(best[k]))
          pooled[k] = best[k] - 2.0 * std::log(pooled[k] / count);
        else
          pooled[k] = best[k];
        open[k] =
            best[k] > log_fresh && (best[k] > log_eps || pooled[k] > log_eps);
      }
    }
  });
}

}  // namespace aia
