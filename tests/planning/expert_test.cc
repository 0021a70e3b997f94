#include "aia/planning/expert.h"

#include <gtest/gtest.h>

#include <limits>

#include "aia/core/error.h"
#include "aia/estimation/filter.h"
#include "aia/planning/decsb.h"
#include "aia/planning/information.h"
#include "aia/planning/registry.h"
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

TEST(ExpertTest, PlanReplayedThroughTheCentralizedFilterMeetsEps) {
  for (std::uint64_t seed : {3, 4, 5}) {
    Team run("seed: " + std::to_string(seed) +
             "\nrobots: {count: 6}\ntargets: {count: 6}\n"
             "workspace: {obstacles: {random: {count: 30}}}\n");
    const SamplingPlan plan = Solve(run, 2000);
    ASSERT_TRUE(plan.found);
    ASSERT_EQ(static_cast<int>(plan.configs.size()), plan.depth + 1);
    EXPECT_EQ(plan.configs[0], run.positions);
    // Replay: every move valid, the centralized filter fed with the
    // measurements the planner predicts (at the means) meets eps exactly at
    // step F*.
    const Lattice& lat = run.world.map.lattice();
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
        p[i] = lat.Point(b);
        for (int k = 0; k < run.world.NumTargets(); ++k) {
          const Vec2 mu = central.PositionMean(0, k);
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
}

TEST(ExpertTest, MoreBudgetNeverYieldsACostlierPlan) {
  Team team(kTen);
  double previous = std::numeric_limits<double>::infinity();
  for (long budget : {0L, 10L, 100L, 1000L, 5000L, 20000L}) {
    const SamplingPlan plan = Solve(team, budget);
    ASSERT_TRUE(plan.found);
    EXPECT_LE(plan.cost, previous) << "budget " << budget;
    previous = plan.cost;
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

}  // namespace
}  // namespace aia
