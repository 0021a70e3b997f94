#include "aia/planning/tours.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <vector>

#include "aia/core/rng.h"

namespace aia {
namespace {

// Points on a line: point p is at coordinate p - 50, target k's region is
// the single point `at[k]`, and a leg is the distance walked.
class LineLegs : public LegOracle {
 public:
  explicit LineLegs(std::vector<int> at) : at_(std::move(at)) {}
  Leg Compute(int from, int, int k) override {
    return {std::abs(at_[k] - from), at_[k]};
  }
  bool TimeVarying(int) const override { return false; }

 private:
  std::vector<int> at_;
};

TEST(ToursTest, OneRobotVisitsTheNearSideFirst) {
  // Robot at 50; targets at 49 and 53. Near first: arrivals 1 and 5
  // (latency 6, makespan 5); far first: 3 and 7 (latency 10).
  LineLegs legs({53, 49});
  TourPlanner planner;
  for (TourObjective objective :
       {TourObjective::kLatency, TourObjective::kMakespan}) {
    const Tours t =
        planner.Plan({50}, {0, 1}, {1.0, 1.0}, {objective, 1000}, legs);
    EXPECT_EQ(t.order[0], (std::vector<int>{1, 0}));
    EXPECT_EQ(t.makespan, 5);
    EXPECT_DOUBLE_EQ(t.latency, 6.0);
  }
}

TEST(ToursTest, TwoRobotsSplitTheLine) {
  // Robots at 40 and 60; targets at 41, 42, 43, 44 and 70: robot 0 walks
  // 41..44 (arrivals 1, 2, 3, 4), robot 1 goes to 70 (10): latency 20 and
  // makespan 10, optimal for both objectives.
  LineLegs legs({41, 42, 43, 44, 70});
  TourPlanner planner;
  for (TourObjective objective :
       {TourObjective::kLatency, TourObjective::kMakespan}) {
    const Tours t = planner.Plan({40, 60}, {4, 3, 2, 1, 0}, {1, 1, 1, 1, 1},
                                 {objective, 10000}, legs);
    EXPECT_EQ(t.order[0], (std::vector<int>{0, 1, 2, 3}));
    EXPECT_EQ(t.order[1], (std::vector<int>{4}));
    EXPECT_DOUBLE_EQ(t.latency, 20.0);
    EXPECT_EQ(t.makespan, 10);
  }
}

TEST(ToursTest, WeightsOrderTheVisits) {
  // One robot at 50; targets at 47 (weight 1) and 52 (weight 10). Latency:
  // 52 first costs 2 * 10 + 7 = 27, 47 first 3 + 8 * 10 = 83. The makespan
  // prefers 52 first too (7 against 8).
  LineLegs legs({47, 52});
  TourPlanner planner;
  const Tours t = planner.Plan({50}, {0, 1}, {1.0, 10.0},
                               {TourObjective::kLatency, 1000}, legs);
  EXPECT_EQ(t.order[0], (std::vector<int>{1, 0}));
  EXPECT_DOUBLE_EQ(t.latency, 27.0);
}

TEST(ToursTest, UnreachableTargetsAreLeftOut) {
  class Legs : public LegOracle {
   public:
    Leg Compute(int from, int, int k) override {
      if (k == 1) return {};
      return {1, from + 1};
    }
    bool TimeVarying(int) const override { return false; }
  } legs;
  TourPlanner planner;
  const Tours t = planner.Plan({0, -1}, {0, 1}, {1, 1}, {}, legs);
  EXPECT_EQ(t.order[0], (std::vector<int>{0}));
  EXPECT_TRUE(t.order[1].empty());  // inactive robot
  EXPECT_EQ(t.unassigned, (std::vector<int>{1}));
}

// Points of a 20 x 20 grid, p = y * 20 + x; target k's region is the single
// point at[k]; a leg is the Manhattan distance.
class GridLegs : public LegOracle {
 public:
  explicit GridLegs(std::vector<int> at) : at_(std::move(at)) {}
  Leg Compute(int from, int, int k) override {
    return {
        std::abs(at_[k] % 20 - from % 20) + std::abs(at_[k] / 20 - from / 20),
        at_[k]};
  }
  bool TimeVarying(int) const override { return false; }

 private:
  std::vector<int> at_;
};

// Regret-2 insertion as defined: every insertion of every remaining target
// into every route evaluated anew, the objective summed from scratch (the
// weights are integers, so the sums are exact whatever their order).
std::vector<std::vector<int>> DefinitionRegret(const std::vector<int>& starts,
                                               std::vector<int> remaining,
                                               const std::vector<double>& w,
                                               TourObjective objective,
                                               LegOracle& legs) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const int n = static_cast<int>(starts.size());
  double weight_sum = 0.0;
  for (int k : remaining) weight_sum += w[k];
  std::vector<std::vector<int>> routes(n);
  auto objective_of = [&](const std::vector<std::vector<int>>& rs) {
    double latency = 0.0;
    int makespan = 0;
    for (int i = 0; i < n; ++i) {
      int t = 0, cur = starts[i];
      for (int k : rs[i]) {
        const Leg leg = legs.Compute(cur, t, k);
        if (leg.steps < 0) return kInf;
        t += (t == 0) ? std::max(leg.steps, 1) : leg.steps;
        cur = leg.end;
        latency += w[k] * t;
      }
      makespan = std::max(makespan, t);
    }
    if (objective == TourObjective::kLatency) return latency + 1e-9 * makespan;
    return makespan + 0.5 * latency / (weight_sum * (makespan + 1.0) + 1e-300);
  };
  while (!remaining.empty()) {
    int pick = -1, pick_robot = -1, pick_pos = -1;
    double pick_key = -kInf, pick_best = kInf;
    for (size_t r = 0; r < remaining.size(); ++r) {
      double best1 = kInf, best2 = kInf;
      int robot1 = -1, pos1 = -1;
      for (int i = 0; i < n; ++i) {
        double robot_best = kInf;
        int robot_pos = -1;
        for (size_t p = 0; p <= routes[i].size(); ++p) {
          std::vector<std::vector<int>> trial = routes;
          trial[i].insert(trial[i].begin() + p, remaining[r]);
          const double obj = objective_of(trial);
          if (obj < robot_best) {
            robot_best = obj;
            robot_pos = static_cast<int>(p);
          }
        }
        if (robot_best < best1) {
          best2 = best1;
          best1 = robot_best;
          robot1 = i;
          pos1 = robot_pos;
        } else if (robot_best < best2) {
          best2 = robot_best;
        }
      }
      if (best1 == kInf) continue;
      const double key = n > 1 ? best2 - best1 : -best1;
      if (key > pick_key || (key == pick_key && best1 < pick_best)) {
        pick_key = key;
        pick_best = best1;
        pick = static_cast<int>(r);
        pick_robot = robot1;
        pick_pos = pos1;
      }
    }
    if (pick < 0) break;
    routes[pick_robot].insert(routes[pick_robot].begin() + pick_pos,
                              remaining[pick]);
    remaining.erase(remaining.begin() + pick);
  }
  return routes;
}

// m targets at random points of the grid (at) and their ids 0..m-1.
void RandomGridTargets(Rng* rng, int m, std::vector<int>* at,
                       std::vector<int>* targets) {
  at->resize(m);
  targets->resize(m);
  for (int k = 0; k < m; ++k) {
    (*at)[k] = static_cast<int>(rng->UniformInt(400));
    (*targets)[k] = k;
  }
}

TEST(ToursTest, InsertionIsRegretInsertionAsDefined) {
  // The planner keeps each route's values with a target inserted until the
  // route changes; with no budget for the local search its tours must be
  // those of the definition, ties included (small grids have many).
  Rng rng(7);
  for (int trial = 0; trial < 60; ++trial) {
    const int n = 1 + static_cast<int>(rng.UniformInt(6));
    const int m = 1 + static_cast<int>(rng.UniformInt(12));
    std::vector<int> starts(n), at(m), targets(m);
    std::vector<double> w(m);
    for (int& s : starts) s = static_cast<int>(rng.UniformInt(400));
    for (int k = 0; k < m; ++k) {
      at[k] = static_cast<int>(rng.UniformInt(400));
      w[k] = 1.0 + static_cast<double>(rng.UniformInt(4));
      targets[k] = m - 1 - k;
    }
    GridLegs legs(at);
    TourPlanner planner;
    for (TourObjective objective :
         {TourObjective::kLatency, TourObjective::kMakespan}) {
      const Tours t = planner.Plan(starts, targets, w, {objective, 0}, legs);
      EXPECT_EQ(t.order, DefinitionRegret(starts, targets, w, objective, legs))
          << "trial " << trial;
    }
  }
}

TEST(ToursTest, TargetsGoToTheirCandidateRobots) {
  // With one candidate robot per target, insertion puts each target in the
  // route of the robot nearest to it (the lower id on a tie); no budget is
  // left for the local search to move it.
  Rng rng(3);
  const int n = 12, m = 30;
  std::vector<int> starts(n), at, targets;
  for (int& s : starts) s = static_cast<int>(rng.UniformInt(400));
  RandomGridTargets(&rng, m, &at, &targets);
  GridLegs legs(at);
  TourPlanner planner;
  TourSettings settings;
  settings.candidates = 1;
  settings.budget = 0;
  const Tours t = planner.Plan(starts, targets, std::vector<double>(m, 1.0),
                               settings, legs);
  std::vector<int> owner(m, -1);
  for (int i = 0; i < n; ++i)
    for (int k : t.order[i]) owner[k] = i;
  for (int k = 0; k < m; ++k) {
    int nearest = 0;
    for (int i = 1; i < n; ++i)
      if (legs.Distance(starts[i], k) < legs.Distance(starts[nearest], k))
        nearest = i;
    EXPECT_EQ(owner[k], nearest) << "target " << k;
  }
}

TEST(ToursTest, PastTheInsertionWorkTheRestJoinTheRouteEnds) {
  // One robot at 50; targets 0..3 at 51, 55, 52 and 60. Regret insertion
  // visits them near first: 51, 52, 55, 60 (arrivals 1, 2, 5, 10, latency
  // 18). With the work for one round only, it inserts the cheapest (51,
  // arrival 1) and the rest join the route's end in their order: 55, 52,
  // 60 (arrivals 5, 8, 16, latency 30). No local search in either.
  LineLegs legs({51, 55, 52, 60});
  TourPlanner planner;
  TourSettings settings;
  settings.budget = 0;
  const std::vector<double> w(4, 1.0);
  const Tours full = planner.Plan({50}, {0, 1, 2, 3}, w, settings, legs);
  EXPECT_EQ(full.order[0], (std::vector<int>{0, 2, 1, 3}));
  EXPECT_DOUBLE_EQ(full.latency, 18.0);
  settings.insert_work = 1;
  const Tours cut = planner.Plan({50}, {0, 1, 2, 3}, w, settings, legs);
  EXPECT_EQ(cut.order[0], (std::vector<int>{0, 1, 2, 3}));
  EXPECT_DOUBLE_EQ(cut.latency, 30.0);
  EXPECT_EQ(cut.makespan, 16);
}

TEST(ToursTest, TheRestJoinTheRouteWhereTheyCostLeast) {
  // Robots at 40 and 60; targets 41, 59, 42, 58 and one no robot reaches.
  // Insertion takes 41 (to robot 0; 59's regret ties and comes later);
  // then, appended in order: 59 to robot 1 (arrival 1, not 19), 42 to
  // robot 0 (2, not 18), 58 to robot 1 (2, not 18); the last unassigned.
  class Legs : public LineLegs {
   public:
    Legs() : LineLegs({41, 59, 42, 58, 0}) {}
    Leg Compute(int from, int t, int k) override {
      return k == 4 ? Leg{} : LineLegs::Compute(from, t, k);
    }
  } legs;
  TourPlanner planner;
  TourSettings settings;
  settings.budget = 0;
  settings.insert_work = 1;
  const Tours t = planner.Plan({40, 60}, {0, 1, 2, 3, 4},
                               std::vector<double>(5, 1.0), settings, legs);
  EXPECT_EQ(t.order[0], (std::vector<int>{0, 2}));
  EXPECT_EQ(t.order[1], (std::vector<int>{1, 3}));
  EXPECT_EQ(t.unassigned, (std::vector<int>{4}));
  EXPECT_DOUBLE_EQ(t.latency, 6.0);
}

TEST(ToursTest, ManyTargetsForOneRobotEndInOneRoute) {
  // Insertion's work grows as M^4 for one robot: 600 targets would take
  // minutes in full. Bounded, the plan ends, and holds every target once.
  Rng rng(11);
  const int m = 600;
  std::vector<int> at, targets;
  RandomGridTargets(&rng, m, &at, &targets);
  GridLegs legs(at);
  TourPlanner planner;
  TourSettings settings;
  settings.insert_work = 100000;
  const Tours t =
      planner.Plan({210}, targets, std::vector<double>(m, 1.0), settings, legs);
  std::vector<int> order = t.order[0];
  std::sort(order.begin(), order.end());
  EXPECT_EQ(order, targets);
  EXPECT_TRUE(t.unassigned.empty());
}

}  // namespace
}  // namespace aia
