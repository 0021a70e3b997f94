#include "aia/runtime/episode.h"

#include <gtest/gtest.h>

#include "aia/runtime/mission.h"
#include "support/test_support.h"

namespace aia {
namespace {

using testing::ScenarioFromYaml;

// A small open mission every policy must finish (the contract test, run over
// every name in the registry).
const char* kSmall =
    "seed: 1\nworkspace: {size: [8, 8], obstacles: {random: {count: 4}}}\n"
    "robots: {count: 3}\ntargets: {count: 3}\nmission: {max_steps: 400}\n";

class PolicyContractTest : public ::testing::TestWithParam<std::string> {};

TEST_P(PolicyContractTest, ReachesSuccessOnASmallScenario) {
  Scenario s = ScenarioFromYaml(kSmall);
  s.policy.name = GetParam();
  auto e = MakeEpisode(s, AllPolicies());
  while (!e->done()) {
    e->Step();
    // Every robot is always on a free lattice point.
    for (int idx : e->robot_lattice())
      EXPECT_TRUE(e->world().map.lattice().Free(idx));
  }
  EXPECT_TRUE(e->success()) << GetParam() << " after " << e->step() << " steps";
  EXPECT_EQ(e->flowtime(), e->step());
  for (int k = 0; k < e->world().NumTargets(); ++k)
    EXPECT_LE(e->MinDet(k), s.mission.eps);
}

INSTANTIATE_TEST_SUITE_P(AllPolicies, PolicyContractTest,
                         ::testing::ValuesIn(AllPolicies().Names()),
                         [](const auto& info) { return info.param; });

TEST(EpisodeTest, FailedRobotStopsMovingAndSensing) {
  Scenario s = ScenarioFromYaml(
      "seed: 2\nrobots: {count: 3}\ntargets: {count: 4}\nmission: {max_steps: "
      "30}\n"
      "communication: {failures: [{robot: 1, step: 5}]}\npolicy: {name: "
      "random}\n");
  auto e = MakeEpisode(s, AllPolicies());
  Vec2 at_failure;
  while (!e->done()) {
    e->Step();
    if (e->step() == 5) at_failure = e->robot_positions()[1];
    if (e->step() > 5) {
      EXPECT_FALSE(e->comm().Active(1));
      EXPECT_LT((e->robot_positions()[1] - at_failure).norm(), 0.02);
      EXPECT_TRUE(e->measurements()[1].empty());
    }
  }
}

TEST(EpisodeTest, StepZeroIsThePriorFusedWithFirstMeasurements) {
  // One robot 1 m from a target: after construction (step 0) its belief has
  // the prior information plus one measurement: Omega = I + r I.
  Scenario s = ScenarioFromYaml(
      "robots: {count: 1, start: [[5.25, 5.25]]}\n"
      "targets: {list: [{position: [6.25, 5.25], prior_mean: [6.25, "
      "5.25]}]}\n");
  s.policy.name = "random";
  auto e = MakeEpisode(s, AllPolicies());
  ASSERT_EQ(e->measurements()[0].size(), 1u);
  const double r = e->measurements()[0][0].precision;
  EXPECT_NEAR(e->beliefs().Omega(0, 0)(0, 0), 1.0 + r, 1e-9);
  EXPECT_NEAR(e->central().Omega(0, 0)(1, 1), 1.0 + r, 1e-9);
  EXPECT_NEAR(e->Det(0, 0), 1.0 / ((1 + r) * (1 + r)), 1e-12);
  EXPECT_TRUE(e->success());
  EXPECT_EQ(e->flowtime(), 0);
  EXPECT_TRUE(e->done());
}

TEST(EpisodeTest, TrackingMissionRunsItsWholeHorizon) {
  Scenario s = ScenarioFromYaml(
      "robots: {count: 1, start: [[5.25, 5.25]]}\n"
      "targets:\n  list:\n    - position: [6.0, 5.25]\n      prior_mean: [6.0, "
      "5.25]\n"
      "      dynamics: {A: [[1, 0], [0, 1]], b: [0.02, 0.0], q: 0.0001}\n"
      "mission: {max_steps: 12, stop_at_success: false}\npolicy: {name: "
      "greedy}\n");
  auto e = MakeEpisode(s, AllPolicies());
  const Vec2 start = e->target_positions()[0];
  while (!e->done()) e->Step();
  EXPECT_EQ(e->step(), 12);
  EXPECT_GT((e->target_positions()[0] - start).x(), 0.1);  // drifted right
  EXPECT_GT(e->localized_steps(), 0);
}

}  // namespace
}  // namespace aia
