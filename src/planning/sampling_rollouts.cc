// The tours and the rollouts that finish a node (planning/sampling_tree.h):
// to the goal by the tours, by the makespan tours, toward the nearest open
// target, or greedily.
#include <algorithm>
#include <cmath>
#include <limits>

#include "aia/core/check.h"
#include "aia/planning/greedy.h"
#include "aia/planning/information.h"
#include "aia/planning/sampling_tree.h"
#include "aia/planning/search.h"
#include "aia/planning/tours.h"
#include "aia/world/lattice.h"
#include "sampling_tree_internal.h"

namespace aia {

// The tours' legs are the tree's own fields, walked.
class SamplingTree::Legs : public LegOracle {
 public:
  explicit Legs(SamplingTree* tree) : tree_(tree) {}
  Leg Compute(int from, int t, int k) override {
    return tree_->ComputeLeg(from, t, k);
  }
  bool TimeVarying(int k) const override {
    return !tree_->targets_[k].is_static;
  }
  int Distance(int from, int k) override {
    return tree_->aims_.FieldAt(0, k)[from];
  }

 private:
  SamplingTree* tree_;
};

int SamplingTree::NextInTour(const std::vector<int>& tour) const {
  for (int k : tour)
    if (open_[k]) return k;
  return -1;
}

Move SamplingTree::StepToward(int q, int k, int depth, Rng* rng) {
  const Lattice& lattice = problem_->map->lattice();
  if (k >= 0) {
    const int* f =
        static_field_[k] ? static_field_[k] : aims_.FieldAt(depth, k).data();
    const int here = f[q];
    if (here > 0) {  // StepDownField
      for (Move m : kMoves) {
        const int v = lattice.Next(q, m);
        if (v >= 0 && f[v] == here - 1) return m;
      }
      return Move::kStay;
    }
    if (here == 0) {  // in the region already: stay inside it if possible
      for (Move m : kMoves) {
        const int v = lattice.Next(q, m);
        if (v >= 0 && f[v] == 0) return m;
      }
    }
  }
  if (rng) return RandomValidMove(lattice, q, *rng);
  for (Move m : kMoves)
    if (lattice.Valid(q, m)) return m;
  return Move::kStay;
}

void SamplingTree::Assign(int node, bool sorted, Rng& rng) {
  const SamplingProblem& p = *problem_;
  const int* pos = arena_.Pos(node);
  const int depth = arena_.depth(node) + 1;
  MarkOpen(node);
  std::copy(open_.begin(), open_.end(), avail_.begin());  // open, not taken
  std::fill(assigned_.begin(), assigned_.end(), -1);
  if (sorted && !use_index_) {
    // The definition, for tests: all pairs, sorted.
    pairs_.clear();
    for (int i = 0; i < n_; ++i) {
      if (!p.active[i]) continue;
      for (int k : open_list_) {
        const int d = aims_.FieldAt(depth, k)[pos[i]];
        if (d >= 0) pairs_.push_back({d, i * m_ + k});
      }
    }
    std::sort(pairs_.begin(), pairs_.end());
    for (const auto& [d, ik] : pairs_) {
      const int i = ik / m_, k = ik % m_;
      if (assigned_[i] >= 0 || !avail_[k]) continue;
      assigned_[i] = k;
      avail_[k] = 0;
    }
  } else if (sorted) {
    // Globally nearest robot-target pairs (distance, then robot, then target)
    // first: a greedy matching. Without listing every pair: each robot's
    // nearest free target (NearestTarget) in a heap of (distance, robot * m +
    // target); an entry whose target was taken meanwhile is replaced by the
    // robot's next nearest free one. The top is then always the first pair of
    // the sorted list of all pairs whose robot and target are both free.
    pairs_.clear();
    for (int i = 0; i < n_; ++i) {
      if (!p.active[i]) continue;
      int d = 0;
      const int k = NearestTarget(pos[i], depth, avail_, &d);
      if (k >= 0) pairs_.push_back({d, i * m_ + k});
    }
    std::make_heap(pairs_.begin(), pairs_.end(), std::greater<>());
    int left = static_cast<int>(open_list_.size());
    while (!pairs_.empty() && left > 0) {
      std::pop_heap(pairs_.begin(), pairs_.end(), std::greater<>());
      const int i = pairs_.back().second / m_, k = pairs_.back().second % m_;
      pairs_.pop_back();
      if (!avail_[k]) {
        int d = 0;
        const int next = NearestTarget(pos[i], depth, avail_, &d);
        if (next >= 0) {
          pairs_.push_back({d, i * m_ + next});
          std::push_heap(pairs_.begin(), pairs_.end(), std::greater<>());
        }
        continue;
      }
      assigned_[i] = k;
      avail_[k] = 0;
      --left;
    }
  } else {
    // Each robot in random order takes its nearest free unlocalized target.
    order_.clear();
    for (int i = 0; i < n_; ++i)
      if (p.active[i]) order_.push_back(i);
    for (size_t a = order_.size(); a > 1; --a)
      std::swap(order_[a - 1], order_[rng.UniformInt(a)]);
    for (int i : order_) {
      int d = 0;
      const int best = NearestTarget(pos[i], depth, avail_, &d);
      if (best >= 0) {
        assigned_[i] = best;
        avail_[best] = 0;
      }
    }
  }
  // Robots left over (more robots than open targets) follow the idle rule:
  // toward the nearest unlocalized target.
  for (int i = 0; i < n_; ++i)
    if (p.active[i] && assigned_[i] < 0)
      assigned_[i] = NearestOpen(pos[i], depth);
}

Leg SamplingTree::ComputeLeg(int from, int t, int k) {
  const Lattice& lattice = problem_->map->lattice();
  const int cap = lattice.size();
  int cur = from;
  for (int s = 0; s <= cap; ++s) {
    const int here = aims_.FieldAt(t + s, k)[cur];
    if (here < 0) return {};
    // Arrived (at the root a robot in the region still needs a step).
    if (here == 0 && t + s > 0) return {s, cur};
    const Move m = StepToward(cur, k, t + s + 1, nullptr);
    if (m == Move::kStay) return {};
    cur = lattice.Next(cur, m);
  }
  return {};
}

void SamplingTree::PlanTours() {
  const SamplingProblem& p = *problem_;
  std::vector<int> starts(n_, -1), targets;
  for (int i = 0; i < n_; ++i)
    if (p.active[i]) starts[i] = p.start[i];
  std::vector<double> weight(m_, 0.0);
  MarkOpen(0);
  for (int k = 0; k < m_; ++k) {
    if (!open_[k]) continue;
    targets.push_back(k);
    weight[k] = BlockDet(arena_.Info(0), k);
  }
  Legs legs(this);
  TourSettings settings;
  settings.budget = tour_budget_;
  settings.objective = TourObjective::kLatency;
  const Tours latency =
      tour_planner_.Plan(starts, targets, weight, settings, legs);
  tours_ = latency.order;
  tour_makespan_ = latency.makespan;
  settings.objective = TourObjective::kMakespan;
  makespan_tours_ =
      tour_planner_.Plan(starts, targets, weight, settings, legs).order;
}

double SamplingTree::GreedyGain(const double* info, int depth, int v) {
  const SamplingProblem& p = *problem_;
  const double log_eps = std::log(p.eps);
  double gain = 0.0;
  if (!any_moving_) {
    // The static targets seen from v, in ascending order as below.
    for (int o = obs_begin_[v]; o < obs_begin_[v + 1]; ++o) {
      const auto& [k, r] = obs_[o];
      if (!open_[k] || r <= 0.0) continue;
      gain += LogDetDrop(std::log(BlockDet(info, k)),
                         std::log(BlockDetAfter(info, k, r)), log_eps);
    }
    return gain;
  }
  const Vec2 there = p.map->lattice().Point(v);
  for (int k = 0; k < m_; ++k) {
    if (!open_[k]) continue;
    double r = 0.0;
    if (targets_[k].is_static) {
      for (int o = obs_begin_[v]; o < obs_begin_[v + 1]; ++o)
        if (obs_[o].first == k) r = obs_[o].second;
    } else {
      r = PredictedPrecision(*p.map, *p.sensor, there,
                             aims_.MeasurePoint(depth, k));
    }
    if (r <= 0.0) continue;
    gain += LogDetDrop(std::log(BlockDet(info, k)),
                       std::log(BlockDetAfter(info, k, r)), log_eps);
  }
  return gain;
}

void SamplingTree::RolloutMoves(int node, RolloutKind kind) {
  const SamplingProblem& p = *problem_;
  const Lattice& lattice = p.map->lattice();
  const int* from = arena_.Pos(node);
  const int depth = arena_.depth(node) + 1;
  const double* info = arena_.Info(node);
  if (kind == RolloutKind::kNearest) {
    Rng unused(0);
    Assign(node, /*sorted=*/true, unused);
  } else {
    MarkOpen(node);
  }
  for (int i = 0; i < n_; ++i) {
    const int q = from[i];
    child_pos_[i] = q;
    if (!p.active[i]) continue;
    int k = -1;
    if (kind == RolloutKind::kNearest) {
      k = assigned_[i];
    } else if (kind == RolloutKind::kGreedy) {
      // The greedy policy's rule (its first choice) on the team's
      // information; where no move gains, toward the nearest open target.
      Move best[kNumMoves];
      int num_valid = 0;
      const auto gain = [&](int v) { return GreedyGain(info, depth, v); };
      if (GreedyMoves(lattice, q, gain, best, &num_valid) > 0) {
        child_pos_[i] = lattice.Next(q, best[0]);
        continue;
      }
      k = NearestOpen(q, depth);
    } else {
      const auto& tours =
          kind == RolloutKind::kTours ? tours_ : makespan_tours_;
      k = NextInTour(tours[i]);
      if (k < 0) k = NearestOpen(q, depth);
    }
    const Move m = StepToward(q, k, depth, nullptr);
    if (m != Move::kStay) child_pos_[i] = lattice.Next(q, m);
  }
}

int SamplingTree::Rollout(RolloutKind kind, const SamplingParams& params) {
  const Lattice& lattice = problem_->map->lattice();
  const int cap = params.max_depth > 0
                      ? params.max_depth
                      : 2 * (lattice.nx() + lattice.ny()) * std::max(1, m_);
  int v = 0;
  while (arena_.unloc(v) > 0 && arena_.depth(v) < cap &&
         static_cast<long>(arena_.size()) < node_cap_) {
    RolloutMoves(v, kind);
    const int child = AddNode(v, child_pos_.data());
    Register(child, params);
    v = child;
  }
  return v;
}

void SamplingTree::SeededRollouts(const SamplingParams& params, int root,
                                  SamplingPlan* plan) {
  PlanTours();
  const std::pair<RolloutKind, const char*> kinds[] = {
      {RolloutKind::kTours, "tours"},
      {RolloutKind::kMakespanTours, "makespan_tours"},
      {RolloutKind::kNearest, "nearest"},
      {RolloutKind::kGreedy, "greedy"}};
  for (const auto& [kind, name] : kinds) {
    const int end = Rollout(kind, params);
    plan->rollouts.push_back(
        {name, arena_.unloc(end) == 0, arena_.depth(end), arena_.cost(end)});
  }
  last_ = root;
}

}  // namespace aia
