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
    if (!ctx.comm->Active(i) || !Deciding(ctx, i)) continue;
    const int p = (*ctx.robot_lattice)[i];
    const Vec2 here = lattice.Point(p);
    for (int k = 0; k < num_targets; ++k)
      PredictBlock(*ctx.beliefs, i, k, &blocks_[k]);

    const auto gain = [&](int q) {
      const Vec2 there = lattice.Point(q);
      double g = 0.0;
      for (int k = 0; k < num_targets; ++k) {
        const PredictedBlock& b = blocks_[k];
        if (b.logdet_sigma <= log_eps) continue;
        if ((b.mu - here).squaredNorm() > reach * reach) continue;
        const double r = PredictedPrecision(*ctx.map, sensor, there, b.mu);
        if (r <= 0.0) continue;
        g += LogDetDrop(b.logdet_sigma, LogDetSigmaAfter(b, r), log_eps);
      }
      return g;
    };
    Move candidates[kNumMoves];
    int num_valid = 0;
    const int num_candidates =
        GreedyMoves(lattice, p, gain, candidates, &num_valid);
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
  const double log_eps = std::log(ctx.eps);
  const int num_blocks = static_cast<int>(blocks_.size());
  aims_.resize(num_blocks);
  open_.assign(num_blocks, 0);
  for (int k = 0; k < num_blocks; ++k) {
    aims_[k] = blocks_[k].mu;
    open_[k] = blocks_[k].logdet_sigma > log_eps ? 1 : 0;
  }
  return toward_.FirstMove(*ctx.map, *ctx.sensor, (*ctx.robot_lattice)[robot],
                           aims_, open_);
}

}  // namespace aia
