#include "aia/planning/decsb.h"

#include "aia/planning/information.h"

namespace aia {

SamplingParams DecSbParams::Sampling() const {
  SamplingParams p;
  p.p_v = p_v;
  p.p_u = p_u;
  p.max_depth = horizon;
  p.max_iterations = iterations;
  p.routing = false;
  // A robot's tree stops at the horizon; a goal (its own belief below eps
  // everywhere) ends the search early, with a short anytime polish.
  p.anytime = iterations / 4;
  return p;
}

DecSbPolicy::DecSbPolicy(const DecSbParams& params)
    : params_(params.Sampling()) {}

void DecSbPolicy::Reset(const Map&, int num_robots, int, std::uint64_t seed) {
  rngs_.clear();
  for (int i = 0; i < num_robots; ++i)
    rngs_.emplace_back(seed, "policy.decsb", i);
  plans_.assign(num_robots, {});
  next_.assign(num_robots, -1);
}

PolicyStatus DecSbPolicy::Decide(const DecisionContext& ctx,
                                 std::vector<Move>* moves) {
  const Lattice& lattice = ctx.map->lattice();
  const int n = static_cast<int>(moves->size());
  const int m = ctx.beliefs->layout().num_targets();
  // What each robot announces this step: the position after its next move,
  // from the plan it made last step, if it is still on that plan.
  for (int j = 0; j < n; ++j) {
    const auto& plan = plans_[j];
    next_[j] =
        (plan.size() >= 3 && plan[1] == (*ctx.robot_lattice)[j]) ? plan[2] : -1;
  }
  PolicyStatus status = PolicyStatus::kOk;
  for (int i = 0; i < n; ++i) {
    (*moves)[i] = Move::kStay;
    if (!ctx.comm->Active(i)) {
      plans_[i].clear();
      continue;
    }
    if (!Deciding(ctx, i)) continue;  // on its way, on its plan
    // Neighbours' announced positions, evaluated on robot i's own means.
    extra_.assign(m, 0.0);
    for (int j : ctx.comm->Neighbors(i)) {
      if (next_[j] < 0) continue;
      const Vec2 q = lattice.Point(next_[j]);
      for (int k = 0; k < m; ++k)
        extra_[k] += PredictedPrecision(*ctx.map, *ctx.sensor, q,
                                        ctx.beliefs->PositionMean(i, k));
    }
    SamplingProblem problem;
    problem.map = ctx.map;
    problem.sensor = ctx.sensor;
    problem.eps = ctx.eps;
    problem.start = {(*ctx.robot_lattice)[i]};
    problem.active = {1};
    problem.belief = ctx.beliefs;
    problem.belief_row = i;
    problem.extra_at_depth1 = extra_;
    const SamplingPlan plan = tree_.Solve(problem, params_, rngs_[i]);
    auto& path = plans_[i];
    path.clear();
    for (const auto& config : plan.configs) path.push_back(config[0]);
    Move move =
        path.size() >= 2 ? MoveBetween(lattice, path[0], path[1]) : Move::kStay;
    if (move == Move::kStay) {  // nothing left to gain within the horizon
      move = RandomValidMove(lattice, path[0], rngs_[i]);
      if (move == Move::kStay) status = PolicyStatus::kNoValidMove;
    }
    (*moves)[i] = move;
  }
  return status;
}

}  // namespace aia
