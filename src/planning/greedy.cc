#include "aia/planning/greedy.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace aia {

void GreedyPolicy::Reset(const Map&, int num_robots, int num_targets,
                         std::uint64_t seed) {
  rngs_.clear();
  for (int i = 0; i < num_robots; ++i)
    rngs_.emplace_back(seed, "policy.greedy", i);
  blocks_.assign(num_targets, {});
}

PolicyStatus GreedyPolicy::Decide(const DecisionContext& ctx,
                                  std::vector<Move>* moves) {
  const Lattice& lattice = ctx.map->lattice();
  const SensorModel& sensor = *ctx.sensor;
  const double log_eps = std::log(ctx.eps);
  const double reach = sensor.range + lattice.step();
  const int num_targets = ctx.beliefs->layout().num_targets();
  PolicyStatus status = PolicyStatus::kOk;
  for (int i = 0; i < static_cast<int>(moves->size()); ++i) {
    (*moves)[i] = Move::kStay;
    if (!ctx.comm->Active(i)) continue;
    const int p = (*ctx.positions)[i];
    const Vec2 here = lattice.Point(p);
    for (int k = 0; k < num_targets; ++k)
      PredictBlock(*ctx.beliefs, i, k, &blocks_[k]);

    double best = 0.0;
    Move candidates[kNumMoves];
    int num_candidates = 0, num_valid = 0;
    for (Move m : kMoves) {
      const int q = lattice.Next(p, m);
      if (q < 0) continue;
      ++num_valid;
      const Vec2 there = lattice.Point(q);
      double gain = 0.0;
      for (int k = 0; k < num_targets; ++k) {
        const PredictedBlock& b = blocks_[k];
        if (b.logdet_sigma <= log_eps) continue;
        if ((b.mu - here).squaredNorm() > reach * reach) continue;
        const double r = PredictedPrecision(*ctx.map, sensor, there, b.mu);
        if (r <= 0.0) continue;
        gain += b.logdet_sigma - std::max(LogDetSigmaAfter(b, r), log_eps);
      }
      const double tol = 1e-12 * std::max(1.0, best);
      if (gain > best + tol) {
        best = gain;
        num_candidates = 0;
        candidates[num_candidates++] = m;
      } else if (gain > 0.0 && gain >= best - tol) {
        candidates[num_candidates++] = m;
      }
    }
    if (num_valid == 0) {
      status = PolicyStatus::kNoValidMove;
      continue;
    }
    Rng& rng = rngs_[i];
    if (num_candidates > 0) {
      (*moves)[i] =
          candidates[num_candidates == 1 ? 0 : rng.UniformInt(num_candidates)];
      continue;
    }
    Move m = TowardNearestTarget(ctx, i);
    if (m == Move::kStay) m = RandomValidMove(lattice, p, rng);  // wander
    (*moves)[i] = m;
  }
  return status;
}

Move GreedyPolicy::TowardNearestTarget(const DecisionContext& ctx, int robot) {
  const Lattice& lattice = ctx.map->lattice();
  const SensorModel& sensor = *ctx.sensor;
  const double log_eps = std::log(ctx.eps);
  const int p = (*ctx.positions)[robot];
  // The targets still above eps in this robot's belief, by the lattice point
  // nearest their mean; their observation points are the points of the
  // (2 span + 1)^2 window around it from which the target is seen.
  const int span =
      static_cast<int>(std::ceil(sensor.range / lattice.step())) + 1;
  const int num_blocks = static_cast<int>(blocks_.size());
  centres_.resize(num_blocks);
  open_.assign(num_blocks, 0);
  bool any_open = false;
  for (int k = 0; k < num_blocks; ++k) {
    if (blocks_[k].logdet_sigma <= log_eps) continue;
    const int c = lattice.NearestPoint(blocks_[k].mu);
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
        if (PredictedPrecision(*ctx.map, sensor, lattice.Point(u),
                               blocks_[k].mu) <= 0.0)
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
  return move;
}

}  // namespace aia
