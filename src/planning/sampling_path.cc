// The path a solve returns (planning/sampling_tree.h), as OMPL's path
// simplifier post-processes a planner's: robots left without useful work are
// rewritten to head for the open targets (RewriteIdle), each robot's last
// useful depth is marked (UsefulUntil), and the plan is filled in.
#include <algorithm>
#include <vector>

#include "aia/planning/information.h"
#include "aia/planning/sampling_tree.h"
#include "aia/world/lattice.h"
#include "sampling_tree_internal.h"

namespace aia {

void SamplingTree::UsefulUntil(const std::vector<int>& path,
                               std::vector<int>* until) {
  const SamplingProblem& p = *problem_;
  const Lattice& lattice = p.map->lattice();
  until->assign(n_, 0);
  for (size_t d = 1; d < path.size(); ++d) {
    MarkOpen(path[d - 1]);
    const int* pos = arena_.Pos(path[d]);
    for (int i = 0; i < n_; ++i) {
      if (!p.active[i]) continue;
      bool useful = false;
      for (int o = obs_begin_[pos[i]]; o < obs_begin_[pos[i] + 1]; ++o)
        useful = useful || open_[obs_[o].first];
      for (int k = 0; k < m_ && !useful && any_moving_; ++k)
        useful = open_[k] && !targets_[k].is_static &&
                 PredictedPrecision(
                     *p.map, *p.sensor, lattice.Point(pos[i]),
                     aims_.MeasurePoint(static_cast<int>(d), k)) > 0.0;
      if (useful) (*until)[i] = static_cast<int>(d);
    }
  }
}

int SamplingTree::RewriteIdle(int end) {
  const SamplingProblem& p = *problem_;
  const Lattice& lattice = p.map->lattice();
  std::vector<int> path(arena_.depth(end) + 1);
  for (int v = end; v >= 0; v = arena_.parent(v)) path[arena_.depth(v)] = v;
  std::vector<int> until;
  UsefulUntil(path, &until);
  bool idle = false;
  for (int i = 0; i < n_; ++i)
    idle = idle || (p.active[i] && until[i] < arena_.depth(end));
  if (!idle) return end;
  // Replay: robots with useful work left keep their moves, the others head
  // for the nearest target the team has not localized. Information only
  // grows, so every target is localized no later than on the original path,
  // and J is no larger.
  int v = 0;
  for (int d = 1; d <= arena_.depth(end) && arena_.unloc(v) > 0; ++d) {
    MarkOpen(v);
    const int* from = arena_.Pos(v);
    const int* planned = arena_.Pos(path[d]);
    for (int i = 0; i < n_; ++i) {
      child_pos_[i] = from[i];
      if (!p.active[i]) continue;
      if (d <= until[i]) {
        child_pos_[i] = planned[i];
        continue;
      }
      const Move m = StepToward(from[i], NearestOpen(from[i], d), d, nullptr);
      if (m != Move::kStay) child_pos_[i] = lattice.Next(from[i], m);
    }
    v = AddNode(v, child_pos_.data());
  }
  if (arena_.unloc(v) != 0 || arena_.cost(v) > arena_.cost(end) + tol_ ||
      arena_.depth(v) > arena_.depth(end))
    return end;  // cannot happen (see above); kept as a guard
  return v;
}

void SamplingTree::ExtractPlan(const SamplingParams& params,
                               SamplingPlan* plan) {
  plan->found = best_ >= 0;
  plan->best_cost = plan->found ? j_min_ : 0.0;
  int end = plan->found ? best_ : best_partial_;
  if (plan->found && params.routing) end = RewriteIdle(end);
  plan->status =
      plan->found ? PolicyStatus::kOk : PolicyStatus::kBudgetExhausted;
  plan->depth = arena_.depth(end);
  plan->cost = arena_.cost(end);
  plan->configs.assign(plan->depth + 1, std::vector<int>(n_));
  plan->det.assign(plan->depth + 1, std::vector<double>(m_));
  std::vector<int> path(plan->depth + 1);
  for (int v = end; v >= 0; v = arena_.parent(v)) {
    const int d = arena_.depth(v);
    path[d] = v;
    std::copy(arena_.Pos(v), arena_.Pos(v) + n_, plan->configs[d].begin());
    for (int k = 0; k < m_; ++k) plan->det[d][k] = BlockDet(arena_.Info(v), k);
  }
  UsefulUntil(path, &plan->useful_until);
  plan->aims.resize(m_);
  for (int k = 0; k < m_; ++k) plan->aims[k] = aims_.MeasurePoint(0, k);
  plan->tour_makespan = tour_makespan_;
  plan->nodes = static_cast<long>(arena_.size());
  plan->iterations = iteration_;
  plan->first_goal_iteration = first_goal_iteration_;
  // What the nodes fill (a reserved arena's untouched pages are not
  // resident).
  plan->arena_bytes = arena_.bytes();
}

}  // namespace aia
