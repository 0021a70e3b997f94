#include "aia/planning/expert.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <limits>
#include <thread>

#include "aia/core/error.h"
#include "aia/estimation/filter.h"
#include "aia/planning/decsb.h"
#include "aia/planning/information.h"
#include "aia/planning/registry.h"
#include "aia/world/lattice.h"
#include "support/team_fixture.h"
#include "support/test_support.h"

namespace aia {
namespace {

using testing::ScenarioFromYaml;

using Team = testing::TeamFixture;

const char* kTen =
    "seed: 3\nrobots: {count: 6}\ntargets: {count: 6}\n"
    "workspace: {obstacles: {random: {count: 30}}}\n";

SamplingPlan Solve(const Team& team, long anytime, std::uint64_t seed = 1) {
  SamplingParams params;
  params.anytime = anytime;
  SamplingTree tree;
  Rng rng(seed, "policy.expert");
  return tree.Solve(ExpertProblem(team.Context()), params, rng);
}

// Replays a plan found from the team's starts: every move valid (inside the
// workspace, no obstacle at either end or swept), and the centralized filter
// fed with the measurements the planner predicts (at the means) meets eps
// exactly at step F*, with the plan's det Sigma at every step.
void ExpectReplayMeetsEps(const Team& run, const SamplingPlan& plan) {
  ASSERT_TRUE(plan.found);
  ASSERT_EQ(static_cast<int>(plan.configs.size()), plan.depth + 1);
  EXPECT_EQ(plan.configs[0], run.positions);
  EXPECT_GE(plan.depth, plan.bound);
  const Lattice& lat = run.world.map.lattice();
  const double range = run.sensor.range;
  BeliefSet central = run.central;
  for (int d = 1; d <= plan.depth; ++d) {
    std::vector<std::vector<Measurement>> z(run.world.NumRobots());
    std::vector<Vec2> p(run.world.NumRobots());
    for (int i = 0; i < run.world.NumRobots(); ++i) {
      const int a = plan.configs[d - 1][i], b = plan.configs[d][i];
      const Move m = MoveBetween(lat, a, b);
      ASSERT_NE(m, Move::kStay) << "robot " << i << " at depth " << d;
      ASSERT_TRUE(lat.Valid(a, m));
      ASSERT_TRUE(lat.Free(b));
      ASSERT_TRUE(run.world.map.PointFree(lat.Point(b)));
      p[i] = lat.Point(b);
      for (int k = 0; k < run.world.NumTargets(); ++k) {
        const Vec2 mu = central.PositionMean(0, k);
        if ((mu - p[i]).squaredNorm() > range * range) continue;
        const double r =
            PredictedPrecision(run.world.map, run.sensor, p[i], mu);
        // y chosen so that the mean stays put: y + p = mu.
        if (r > 0) z[i].push_back({k, mu - p[i], r});
      }
    }
    CentralUpdate(z, p, &central);
    bool all = true;
    for (int k = 0; k < run.world.NumTargets(); ++k) {
      EXPECT_NEAR(central.DetCovariance(0, k), plan.det[d][k],
                  1e-9 * plan.det[d][k]);
      all = all && central.DetCovariance(0, k) <= run.scenario.mission.eps;
    }
    EXPECT_EQ(all, d == plan.depth) << "depth " << d;
  }
}

TEST(ExpertTest, PlanReplayedThroughTheCentralizedFilterMeetsEps) {
  for (std::uint64_t seed : {3, 4, 5}) {
    Team run("seed: " + std::to_string(seed) +
             "\nrobots: {count: 6}\ntargets: {count: 6}\n"
             "workspace: {obstacles: {random: {count: 30}}}\n");
    ExpectReplayMeetsEps(run, Solve(run, 2000));
  }
}

// Issue 19: the expert at scale, in the paper's obstacle density (750 boxes
// per 100 x 100 m); docs/design.md, Policies.
std::string Crowd(int count, double side, int boxes, int seed) {
  return "seed: " + std::to_string(seed) + "\nworkspace: {size: [" +
         std::to_string(side) + ", " + std::to_string(side) +
         "], obstacles: {random: {count: " + std::to_string(boxes) +
         "}}}\nrobots: {count: " + std::to_string(count) +
         "}\ntargets: {count: " + std::to_string(count) + "}\n";
}

TEST(ExpertTest, PlanForHundredsOfRobotsMeetsEps) {
  Team run(Crowd(300, 55.0, 250, 2));
  ExpectReplayMeetsEps(run, Solve(run, 500));
}

// 40 robots packed in the lower left corner of a 30 x 30 m world with 60
// targets: far targets, so that the nodes' lower bounds prune.
std::string Corner() {
  std::string starts;
  for (int i = 0; i < 40; ++i)
    starts += std::string(i ? ", " : "") + "[" +
              std::to_string(0.25 + 0.5 * (i % 8)) + ", " +
              std::to_string(0.25 + 0.5 * (i / 8)) + "]";
  return "seed: 8\nworkspace: {size: [30, 30], obstacles: {random: {count: "
         "60}}}\nrobots: {count: 40, start: [" +
         starts + "]}\ntargets: {count: 60}\n";
}

TEST(ExpertTest, SpatialIndexesChangeNoPlan) {
  // The indexes of open targets and of robots and the heap of the
  // nearest-first matching give the plans of the linear scans and of the
  // sorted list of all pairs. Some robots inactive, and a world with few
  // robots and many targets.
  for (const auto& [yaml, inactive] :
       {std::pair{Crowd(120, 32.0, 120, 4), 0},
        std::pair{Crowd(100, 30.0, 100, 5), 7}, std::pair{Corner(), 0},
        std::pair{std::string("seed: 6\nrobots: {count: 12}\n"
                              "targets: {count: 60}\n"
                              "workspace: {obstacles: {random: {}}}\n"),
                  0}}) {
    Team team(yaml);
    SamplingProblem problem = ExpertProblem(team.Context());
    for (size_t i = 0; i < problem.active.size(); i += 1 + inactive)
      if (inactive > 0) problem.active[i] = 0;
    SamplingPlan plans[2];
    for (int linear = 0; linear < 2; ++linear) {
      SamplingParams params;
      params.anytime = 1500;
      params.spatial_index = linear == 0;
      SamplingTree tree;
      Rng rng(2, "policy.expert");
      plans[linear] = tree.Solve(problem, params, rng);
    }
    ASSERT_TRUE(plans[0].found);
    EXPECT_EQ(plans[0].configs, plans[1].configs);
    EXPECT_EQ(plans[0].cost, plans[1].cost);
    EXPECT_EQ(plans[0].best_cost, plans[1].best_cost);
    EXPECT_EQ(plans[0].nodes, plans[1].nodes);
    EXPECT_EQ(plans[0].useful_until, plans[1].useful_until);
    ASSERT_EQ(plans[0].rollouts.size(), plans[1].rollouts.size());
    for (size_t r = 0; r < plans[0].rollouts.size(); ++r)
      EXPECT_EQ(plans[0].rollouts[r].cost, plans[1].rollouts[r].cost);
  }
}

TEST(ExpertTest, MoreBudgetNeverYieldsACostlierPlan) {
  Team team(kTen);
  const double tol = kGoalTolerance * team.scenario.mission.eps;
  double previous = std::numeric_limits<double>::infinity();
  for (long budget : {0L, 10L, 100L, 1000L, 5000L, 20000L}) {
    const SamplingPlan plan = Solve(team, budget);
    ASSERT_TRUE(plan.found);
    // The cheapest goal found never gets costlier; the plan returned is
    // within the tolerance of it.
    EXPECT_LE(plan.best_cost, previous) << "budget " << budget;
    EXPECT_LE(plan.cost, plan.best_cost + tol) << "budget " << budget;
    previous = plan.best_cost;
  }
}

// A corridor 20 m long and 1 m wide (two lattice rows), targets 0.5 m from
// either end. A point sees a target within 2 m: the left one from x <= 2.25,
// the right one from x >= 17.75.
const char* kCorridor =
    "workspace: {size: [20.0, 1.0]}\n"
    "targets: {list: [{position: [0.5, 0.5], prior_mean: [0.5, 0.5]},\n"
    "                 {position: [19.5, 0.5], prior_mean: [19.5, 0.5]}]}\n";

TEST(ExpertTest, CorridorWithTargetsAtBothEnds) {
  // One robot at x = 10.25: right first (15 steps to x = 17.75), then back to
  // x = 2.25 (31 steps): 46. Left first would take 16 + 31 = 47.
  Team one(std::string("robots: {count: 1, start: [[10.25, 0.25]]}\n") +
           kCorridor);
  SamplingPlan plan = Solve(one, 2000);
  ASSERT_TRUE(plan.found);
  EXPECT_EQ(plan.depth, 46);
  EXPECT_EQ(plan.bound, 16);  // the farther target's region, 16 steps away
  // Two robots side by side: one each way, 15 steps.
  Team two(std::string(
               "robots: {count: 2, start: [[9.75, 0.25], [10.25, 0.25]]}\n") +
           kCorridor);
  plan = Solve(two, 2000);
  ASSERT_TRUE(plan.found);
  EXPECT_EQ(plan.depth, 15);
  EXPECT_EQ(plan.bound, 15);
}

// A ring: a 10 x 10 m workspace around a 7 x 7 m block, corridors three
// lattice points wide (0.25-1.25 and 8.75-9.75). Targets in the middle of the
// right, top and left corridors; robots start in the middle of the bottom
// one. A target is seen from its own corridor within 2 m: the right one
// from x >= 8.75, 3.25 <= y <= 6.75; the top one from y >= 8.75,
// 3.25 <= x <= 6.75; the left one from x <= 1.25, 3.25 <= y <= 6.75.
const char* kRing =
    "workspace: {size: [10.0, 10.0], obstacles: {boxes: [{center: [5.0, "
    "5.0], size: [7.0, 7.0]}]}}\n"
    "targets: {list: [{position: [9.25, 5.0], prior_mean: [9.25, 5.0]},\n"
    "                 {position: [5.0, 9.25], prior_mean: [5.0, 9.25]},\n"
    "                 {position: [0.75, 5.0], prior_mean: [0.75, 5.0]}]}\n";

TEST(ExpertTest, RingIsTravelledOneWay) {
  // One robot at (5.25, 0.75): right (12 steps to (8.75, 3.25)), top (15 to
  // (6.75, 8.75)), left (15 to (1.25, 6.75)): 42. The other way round takes
  // 13 + 15 + 15 = 43.
  Team one(std::string("robots: {count: 1, start: [[5.25, 0.75]]}\n") + kRing);
  SamplingPlan plan = Solve(one, 5000);
  ASSERT_TRUE(plan.found);
  EXPECT_EQ(plan.depth, 42);
  // The top target's region is 27 steps away (the right way round).
  EXPECT_EQ(plan.bound, 27);
  // Two robots at (5.25, 0.75) and (5.75, 0.75): one takes the left target
  // (13), the other the right one (11) and then the top one (15): 26.
  Team two(
      std::string("robots: {count: 2, start: [[5.25, 0.75], [5.75, 0.75]]}\n") +
      kRing);
  plan = Solve(two, 5000);
  ASSERT_TRUE(plan.found);
  EXPECT_EQ(plan.depth, 26);
}

TEST(ExpertTest, NeverLongerThanItsGreedyRollout) {
  for (std::uint64_t seed = 0; seed < 50; ++seed) {
    Team team("seed: " + std::to_string(seed) +
              "\nrobots: {count: 10}\ntargets: {count: 10}\n"
              "workspace: {obstacles: {random: {}}}\n");
    const SamplingPlan plan = Solve(team, 2000);
    ASSERT_TRUE(plan.found) << "seed " << seed;
    ASSERT_EQ(plan.rollouts.size(), 4u);
    for (const RolloutResult& r : plan.rollouts) {
      if (!r.found) continue;
      // On the tree's own model: never costlier than a seeded rollout, and
      // never longer than the greedy rule's.
      EXPECT_LE(plan.best_cost, r.cost) << r.name << ", seed " << seed;
      if (r.name == "greedy") EXPECT_LE(plan.depth, r.depth) << "seed " << seed;
    }
    EXPECT_GE(plan.depth, plan.bound) << "seed " << seed;
  }
}

TEST(ExpertTest, UnseeablePriorMeanStillGetsAPlan) {
  // The prior mean lies inside a box that no lattice point sees into; the
  // target itself stands beside it. The plan aims at the nearest part of
  // the prior that a reachable point sees, and the executed plan reaches it.
  Team team(
      "workspace: {size: [10.0, 10.0], obstacles: {boxes: [{center: [5.0, "
      "5.0], size: [3.0, 3.0]}]}}\n"
      "robots: {count: 1, start: [[1.25, 1.25]]}\n"
      "targets: {list: [{position: [5.0, 7.0], prior_mean: [5.0, 5.0], "
      "prior_sigma: 1.0}]}\n");
  const SamplingPlan plan = Solve(team, 1000);
  ASSERT_TRUE(plan.found);
  ASSERT_EQ(plan.aims.size(), 1u);
  EXPECT_TRUE(team.world.map.PointFree(plan.aims[0]));
  EXPECT_LE((plan.aims[0] - Vec2(5.0, 5.0)).norm(), 4.0 + 1e-9);  // <= 4 sigma
}

TEST(ExpertTest, MissedPointsAreNotSearchedAgain) {
  // A robot that stood where the prior mean was in sight and measured
  // nothing rules that out: the plan aims where none of those points sees.
  Team team(
      "robots: {count: 1, start: [[5.25, 5.25]]}\n"
      "targets: {list: [{position: [9.75, 5.25], prior_mean: [9.75, "
      "5.25]}]}\n");
  SamplingProblem problem = ExpertProblem(team.Context());
  const Lattice& lat = team.world.map.lattice();
  const int tried = lat.NearestPoint(Vec2(8.25, 5.25));
  problem.missed = {{tried}};
  SamplingParams params;
  params.anytime = 1000;
  SamplingTree tree;
  Rng rng(1, "policy.expert");
  const SamplingPlan plan = tree.Solve(problem, params, rng);
  ASSERT_TRUE(plan.found);
  EXPECT_GT((plan.aims[0] - lat.Point(tried)).norm(), team.sensor.range);
}

TEST(ExpertTest, IdleRobotsHeadForTheNearestOpenTarget) {
  // After its last useful measurement, a robot's every move shortens its BFS
  // distance to a target still above eps (by the plan's own det).
  for (std::uint64_t seed : {1, 2, 3}) {
    Team team("seed: " + std::to_string(seed) +
              "\nrobots: {count: 10}\ntargets: {count: 4}\n"
              "workspace: {obstacles: {random: {}}}\n");
    const SamplingPlan plan = Solve(team, 2000);
    ASSERT_TRUE(plan.found);
    const Lattice& lat = team.world.map.lattice();
    std::vector<std::vector<int>> field(plan.aims.size());
    std::vector<int> queue;
    for (size_t k = 0; k < plan.aims.size(); ++k) {
      std::vector<int> region;
      for (int q = 0; q < lat.size(); ++q)
        if (lat.Free(q) && PredictedPrecision(team.world.map, team.sensor,
                                              lat.Point(q), plan.aims[k]) > 0)
          region.push_back(q);
      BfsDistances(lat, region.data(), static_cast<int>(region.size()),
                   &field[k], &queue);
    }
    for (int i = 0; i < team.world.NumRobots(); ++i) {
      for (int d = plan.useful_until[i] + 1; d <= plan.depth; ++d) {
        const int a = plan.configs[d - 1][i], b = plan.configs[d][i];
        int nearest = -1;
        for (size_t k = 0; k < field.size(); ++k) {
          if (plan.det[d - 1][k] <= team.scenario.mission.eps) continue;
          if (nearest < 0 || field[k][a] < field[nearest][a])
            nearest = static_cast<int>(k);
        }
        ASSERT_GE(nearest, 0);
        if (field[nearest][a] > 0)
          EXPECT_EQ(field[nearest][b], field[nearest][a] - 1)
              << "seed " << seed << ", robot " << i << ", depth " << d;
      }
    }
  }
}

TEST(ExpertTest, SameSeedSamePlan) {
  Team team(kTen);
  const SamplingPlan a = Solve(team, 3000, 9), b = Solve(team, 3000, 9);
  EXPECT_EQ(a.configs, b.configs);
  EXPECT_EQ(a.cost, b.cost);
  EXPECT_EQ(a.nodes, b.nodes);
  // The tree reuses its arena: solving twice on one tree gives the same plan.
  SamplingTree tree;
  SamplingParams params;
  params.anytime = 3000;
  Rng r1(9, "policy.expert"), r2(9, "policy.expert");
  const SamplingPlan c = tree.Solve(ExpertProblem(team.Context()), params, r1);
  const SamplingPlan d = tree.Solve(ExpertProblem(team.Context()), params, r2);
  EXPECT_EQ(c.configs, a.configs);
  EXPECT_EQ(d.configs, a.configs);
}

TEST(ExpertTest, AlreadyLocalizedTeamNeedsNoMove) {
  Team team(
      "robots: {count: 1, start: [[5.25, 5.25]]}\n"
      "targets: {list: [{position: [6.0, 5.25], prior_sigma: 0.01}]}\n");
  const SamplingPlan plan = Solve(team, 100);
  EXPECT_TRUE(plan.found);
  EXPECT_EQ(plan.depth, 0);
}

TEST(ExpertTest, ShortestPlanForOneRobotOneTarget) {
  // One robot 4.5 m left of a target in the open: it must come within 2 m
  // (sensor range): five moves right end 2.0 m away, so F* = 5.
  Team team(
      "robots: {count: 1, start: [[5.25, 5.25]]}\n"
      "targets: {list: [{position: [9.75, 5.25], prior_mean: [9.75, "
      "5.25]}]}\n");
  const SamplingPlan plan = Solve(team, 2000);
  ASSERT_TRUE(plan.found);
  EXPECT_EQ(plan.depth, 5);
}

TEST(ExpertTest, BadParameterIsAnInputError) {
  Scenario s = ScenarioFromYaml(
      "robots: {count: 1}\ntargets: {count: 1}\npolicy:\n  name: expert\n  "
      "p_v: 1.5\n");
  try {
    BuiltinPolicies().Resolve(s);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.Format(),
              "test.yaml:5: policy.p_v: must be a number in [0, 1], got 1.5");
  }
}

TEST(DecSbTest, WithoutEdgesEachRobotPlansAlone) {
  // Three robots, no communication (range 0): robot i's moves must be the
  // ones it would choose as the only robot in the world (same belief, same
  // position, same random stream).
  const std::string yaml =
      "seed: 4\nrobots: {count: 3, start: [[2.25, 2.25], [10.25, 10.25], "
      "[17.25, 3.25]]}\n"
      "targets: {count: 5}\n";
  CommParams none;
  none.mode = CommMode::kRange;
  none.range = 1e-6;
  Team team(yaml, none);
  DecSbPolicy together{DecSbParams{}};
  together.Reset(team.world.map, 3, team.world.NumTargets(), 11);
  std::vector<Move> moves(3);
  together.Decide(team.Context(), &moves);
  for (int i = 0; i < 3; ++i) {
    // The same robot alone: a one-robot view with its own belief row.
    DecSbPolicy alone{DecSbParams{}};
    alone.Reset(team.world.map, 3, team.world.NumTargets(), 11);
    std::vector<Move> one(3, Move::kStay);
    // The others have failed: they neither plan nor send anything.
    Team solo = team;
    CommNetwork only(none, 3, {{(i + 1) % 3, 0}, {(i + 2) % 3, 0}}, 1);
    std::vector<Vec2> p;
    for (int idx : solo.positions)
      p.push_back(solo.world.map.lattice().Point(idx));
    only.Update(0, p);
    solo.comm = only;
    alone.Decide(solo.Context(), &one);
    EXPECT_EQ(one[i], moves[i]) << "robot " << i;
  }
}

// Issue 19: Dec-SB at the largest horizon and budget its ranges allow,
// three trees at once (as aia eval's threads run them), reached 3.6 GB
// although a tree stops growing at 1 GiB. Large solves now share one
// budget for the process (kMaxTreeBytes; they wait for each other; the
// plans do not change), and give their memory back when done. Checked here
// with a budget of 128 MiB, as a GiB's trees take minutes to grow: three
// trees that did not share it would take 384 MiB.
TEST(DecSbTest, LargeTreesSolvedAtOnceShareTheProcesssBudget) {
  const double budget_mib = 128.0;
  EXPECT_EQ(TreeBudgetBytes(), kMaxTreeBytes);
  SetTreeBudgetBytes(budget_mib * (1 << 20));
  const Team team(
      "seed: 7\nrobots: {count: 10}\ntargets: {count: 10}\n"
      "workspace: {obstacles: {random: {count: 30}}}\n");
  DecSbParams huge;
  huge.horizon = 1000;
  huge.iterations = 10000000;
  const SamplingParams params = huge.Sampling();
  // The trees outlive their solves, as a policy's tree does.
  std::vector<SamplingTree> trees(4);
  const auto solve = [&](int robot, SamplingTree* tree) {
    SamplingProblem problem;
    problem.map = &team.world.map;
    problem.sensor = &team.sensor;
    problem.eps = team.scenario.mission.eps;
    problem.start = {team.positions[robot]};
    problem.active = {1};
    problem.belief = &team.beliefs;
    problem.belief_row = robot;
    problem.extra_at_depth1.assign(team.world.NumTargets(), 0.0);
    Rng rng(1, "policy.decsb", robot);
    return tree->Solve(problem, params, rng);
  };
  std::vector<SamplingPlan> plans(3);
  std::vector<std::thread> threads;
  for (int t = 0; t < 3; ++t)
    threads.emplace_back([&, t] { plans[t] = solve(t, &trees[t]); });
  for (std::thread& t : threads) t.join();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const double peak_mib = usage.ru_maxrss / 1024.0;  // Linux: KiB
  for (const SamplingPlan& plan : plans)
    EXPECT_GT(plan.nodes, 150000);  // each tree did grow large
  EXPECT_LT(peak_mib, budget_mib + 128.0);
  // Solved alone, the same plan.
  const SamplingPlan alone = solve(1, &trees[3]);
  EXPECT_EQ(alone.configs, plans[1].configs);
  EXPECT_EQ(alone.nodes, plans[1].nodes);
}

}  // namespace
}  // namespace aia
