#include "aia/planning/decsb.h"

#include "aia/core/error.h"
#include "aia/planning/expert.h"
#include "aia/planning/information.h"
#include "aia/planning/random_policy.h"

namespace aia {

DecSbPolicy::DecSbPolicy(const Scenario& scenario) {
  CheckPolicyParams(scenario, {"p_v", "p_u", "horizon", "iterations"});
  // Reuse the expert's checked readers for the shared keys.
  Scenario shared = scenario;
  shared.policy.params.erase("horizon");
  shared.policy.params.erase("iterations");
  params_ = ExpertParams(shared);
  const auto& p = scenario.policy.params;
  params_.max_depth = 15;
  params_.max_iterations = 300;
  if (auto it = p.find("horizon"); it != p.end()) {
    if (it->second < 1 || it->second > 1000 ||
        it->second != static_cast<int>(it->second))
      throw InputError(scenario.file, scenario.LineOf("policy.horizon"),
                       "policy.horizon", "must be an integer in [1, 1000]");
    params_.max_depth = static_cast<int>(it->second);
  }
  if (auto it = p.find("iterations"); it != p.end()) {
    if (it->second < 1 || it->second > 1e7 ||
        it->second != static_cast<long>(it->second))
      throw InputError(scenario.file, scenario.LineOf("policy.iterations"),
                       "policy.iterations",
                       "must be an integer in [1, 10000000]");
    params_.max_iterations = static_cast<long>(it->second);
  }
  // A robot's tree stops at the horizon; a goal (its own belief below eps
  // everywhere) ends the search early, with a short anytime polish.
  params_.anytime = params_.max_iterations / 4;
}

void DecSbPolicy::Reset(const World& world, std::uint64_t seed) {
  rngs_.clear();
  for (int i = 0; i < world.NumRobots(); ++i)
    rngs_.emplace_back(seed, "policy.decsb", i);
  plans_.assign(world.NumRobots(), {});
  next_.assign(world.NumRobots(), -1);
}

PolicyStatus DecSbPolicy::Decide(const DecisionContext& ctx,
                                 std::vector<Move>* moves) {
  const Lattice& lattice = ctx.world->lattice;
  const int n = static_cast<int>(moves->size());
  const int m = ctx.beliefs->layout().num_targets();
  // What each robot announces this step: the position after its next move,
  // from the plan it made last step, if it is still on that plan.
  for (int j = 0; j < n; ++j) {
    const auto& plan = plans_[j];
    next_[j] =
        (plan.size() >= 3 && plan[1] == (*ctx.positions)[j]) ? plan[2] : -1;
  }
  PolicyStatus status = PolicyStatus::kOk;
  for (int i = 0; i < n; ++i) {
    (*moves)[i] = Move::kStay;
    if (!ctx.comm->Active(i)) {
      plans_[i].clear();
      continue;
    }
    // Neighbours' announced positions, evaluated on robot i's own means.
    extra_.assign(m, 0.0);
    for (int j : ctx.comm->Neighbors(i)) {
      if (next_[j] < 0) continue;
      const Vec2 q = lattice.Point(next_[j]);
      for (int k = 0; k < m; ++k)
        extra_[k] += PredictedPrecision(*ctx.world, *ctx.sensor, q,
                                        ctx.beliefs->PositionMean(i, k));
    }
    SamplingProblem problem;
    problem.world = ctx.world;
    problem.sensor = ctx.sensor;
    problem.eps = ctx.eps;
    problem.start = {(*ctx.positions)[i]};
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
