#include <gtest/gtest.h>

#include <cmath>

#include "aia/core/error.h"
#include "aia/estimation/filter.h"
#include "aia/planning/greedy.h"
#include "aia/planning/information.h"
#include "aia/planning/random_policy.h"
#include "aia/planning/registry.h"
#include "support/team_fixture.h"
#include "support/test_support.h"

namespace aia {
namespace {

using testing::ScenarioFromYaml;

using PolicyFixture = testing::TeamFixture;

TEST(InformationTest, PredictedPrecisionHonoursRangeAndSight) {
  PolicyFixture s(
      "robots: {count: 1, start: [[1.25, 1.25]]}\ntargets: {count: 1}\n"
      "workspace: {obstacles: {boxes: [{center: [5, 5], size: [0.4, 4]}]}}\n");
  // 1.5 m in the open: 1 / (0.01 + 0.05 * 1.5)^2.
  EXPECT_NEAR(PredictedPrecision(s.world.map, s.sensor, {2, 8}, {3.5, 8}),
              1.0 / (0.085 * 0.085), 1e-9);
  EXPECT_EQ(PredictedPrecision(s.world.map, s.sensor, {2, 8}, {4.5, 8}),
            0.0);  // 2.5 m
  EXPECT_EQ(PredictedPrecision(s.world.map, s.sensor, {4.2, 5}, {5.8, 5}),
            0.0);  // behind the wall
}

TEST(InformationTest, LogDetAfterMeasurementByHand) {
  PredictedBlock b;
  b.dim = 2;
  b.omega.topLeftCorner<2, 2>() << 2, 1, 1, 3;  // det 5
  EXPECT_NEAR(LogDetSigmaAfter(b, 0.0), -std::log(5.0), 1e-12);
  EXPECT_NEAR(LogDetSigmaAfter(b, 1.0), -std::log(3 * 4 - 1.0), 1e-12);
  b.dim = 4;
  b.omega.setIdentity();
  b.omega(0, 0) = 2;
  EXPECT_NEAR(LogDetSigmaAfter(b, 1.0), -std::log(3.0 * 2.0), 1e-12);
}

TEST(RandomPolicyTest, ReturnsValidMovesAndIsReproducible) {
  PolicyFixture s(
      "seed: 2\nrobots: {count: 8}\ntargets: {count: 3}\n"
      "workspace: {obstacles: {random: {count: 30}}}\n");
  RandomPolicy a, b;
  a.Reset(s.world.map, 8, s.world.NumTargets(), 5);
  b.Reset(s.world.map, 8, s.world.NumTargets(), 5);
  std::vector<Move> ma(8), mb(8);
  for (int t = 0; t < 20; ++t) {
    a.Decide(s.Context(), &ma);
    b.Decide(s.Context(), &mb);
    EXPECT_EQ(ma, mb);
    for (int i = 0; i < 8; ++i)
      EXPECT_TRUE(s.world.map.lattice().Valid(s.positions[i], ma[i]));
  }
}

TEST(GreedyPolicyTest, MovesTowardANearbyTarget) {
  // Target 2.25 m to the right of the robot, prior mean on it: only the move
  // right brings it into range.
  PolicyFixture s(
      "robots: {count: 1, start: [[5.25, 5.25]]}\n"
      "targets: {list: [{position: [7.5, 5.25], prior_mean: [7.5, 5.25]}]}\n");
  GreedyPolicy g;
  g.Reset(s.world.map, 1, s.world.NumTargets(), 1);
  std::vector<Move> m(1);
  g.Decide(s.Context(), &m);
  EXPECT_EQ(m[0], Move::kRight);
}

TEST(GreedyPolicyTest, FallsBackToShortestPathTowardTheNearestTarget) {
  // Far from every target: no move gains, so the robot walks a shortest
  // lattice path toward the nearer target (the left one), around a wall.
  PolicyFixture s(
      "robots: {count: 1, start: [[10.25, 10.25]]}\n"
      "targets: {list: [{position: [2.0, 10.25], prior_mean: [2.0, 10.25]},"
      " {position: [19.5, 19.5], prior_mean: [19.5, 19.5]}]}\n"
      "workspace: {obstacles: {boxes: [{center: [8.0, 10.0], size: [0.4, "
      "3.0]}]}}\n");
  GreedyPolicy g;
  g.Reset(s.world.map, 1, s.world.NumTargets(), 1);
  std::vector<Move> m(1);
  std::vector<int> dist, queue;
  // BFS distance to the points that observe the left target.
  std::vector<int> goals;
  for (int q = 0; q < s.world.map.lattice().size(); ++q)
    if (s.world.map.lattice().Free(q) &&
        PredictedPrecision(s.world.map, s.sensor, s.world.map.lattice().Point(q),
                           {2.0, 10.25}) > 0)
      goals.push_back(q);
  BfsDistances(s.world.map.lattice(), goals.data(), static_cast<int>(goals.size()),
               &dist, &queue);
  for (int step = 0; step < 40 && dist[s.positions[0]] > 0; ++step) {
    const int before = dist[s.positions[0]];
    g.Decide(s.Context(), &m);
    const int next = s.world.map.lattice().Next(s.positions[0], m[0]);
    ASSERT_GE(next, 0) << "greedy chose an invalid move";
    s.positions[0] = next;
    EXPECT_EQ(dist[next], before - 1);  // every step is on a shortest path
  }
  EXPECT_EQ(dist[s.positions[0]], 0);
}

TEST(GreedyPolicyTest, IgnoresTargetsAlreadyBelowEps) {
  // The near target is already localized in the robot's belief, the far one
  // is not: the robot heads for the far one (down), not the near one (right).
  PolicyFixture s(
      "robots: {count: 1, start: [[10.25, 10.25]]}\n"
      "targets: {list: [{position: [12.5, 10.25], prior_mean: [12.5, 10.25]},"
      " {position: [10.25, 2.0], prior_mean: [10.25, 2.0]}]}\n");
  s.beliefs.Omega(0, 0) *= 100.0;  // det Sigma = 1e-4 <= eps
  s.beliefs.Xi(0, 0) *= 100.0;
  GreedyPolicy g;
  g.Reset(s.world.map, 1, s.world.NumTargets(), 1);
  std::vector<Move> m(1);
  g.Decide(s.Context(), &m);
  EXPECT_EQ(m[0], Move::kDown);
}

TEST(RegistryTest, UnknownNameListsTheValidOnes) {
  const PolicyRegistry r = BuiltinPolicies();
  EXPECT_TRUE(r.Has("random"));
  EXPECT_TRUE(r.Has("greedy"));
  Scenario s = ScenarioFromYaml(
      "robots: {count: 1}\ntargets: {count: 1}\npolicy: {name: nope}\n");
  try {
    r.Resolve(s);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "policy.name");
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(e.message().find("random"), std::string::npos);
  }
}

TEST(RegistryTest, UnknownPolicyParameterIsAnError) {
  Scenario s = ScenarioFromYaml(
      "robots: {count: 1}\ntargets: {count: 1}\npolicy:\n  name: greedy\n  "
      "budget: 3\n");
  try {
    BuiltinPolicies().Resolve(s);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "policy.budget");
    EXPECT_EQ(e.line(), 5);
    EXPECT_EQ(e.message(), "unknown parameter for policy 'greedy' (valid: none)");
  }
}

}  // namespace
}  // namespace aia
