#include "aia/planning/greedy.h"

#include <algorithm>
#include <cmath>

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
  // BFS from the robot, remembering each point's first move.
  const int n = lattice.size();
  dist_.assign(n, -1);
  first_.assign(n, Move::kStay);
  queue_.resize(n);
  size_t head = 0, tail = 0;
  dist_[p] = 0;
  queue_[tail++] = p;
  while (head < tail) {
    const int u = queue_[head++];
    for (Move m : kMoves) {
      const int v = lattice.Next(u, m);
      if (v < 0 || dist_[v] >= 0) continue;
      dist_[v] = dist_[u] + 1;
      first_[v] = (u == p) ? m : first_[u];
      queue_[tail++] = v;
    }
  }
  int best = -1, best_dist = 0;
  const double step = lattice.step();
  const int span = static_cast<int>(std::ceil(sensor.range / step)) + 1;
  for (const PredictedBlock& b : blocks_) {
    if (b.logdet_sigma <= log_eps) continue;
    const int c = lattice.NearestPoint(b.mu);
    const int cx = lattice.Ix(c), cy = lattice.Iy(c);
    for (int iy = std::max(0, cy - span);
         iy <= std::min(lattice.ny() - 1, cy + span); ++iy) {
      for (int ix = std::max(0, cx - span);
           ix <= std::min(lattice.nx() - 1, cx + span); ++ix) {
        const int q = lattice.Index(ix, iy);
        const int d = dist_[q];
        if (d < 1 || (best >= 0 && d >= best_dist)) continue;
        if (PredictedPrecision(*ctx.map, sensor, lattice.Point(q), b.mu) <= 0.0)
          continue;
        best = q;
        best_dist = d;
      }
    }
  }
  return best < 0 ? Move::kStay : first_[best];
}

}  // namespace aia
