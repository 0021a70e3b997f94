#include "aia/planning/search.h"

#include <gtest/gtest.h>

#include <cmath>

#include "aia/world/lattice.h"
#include "support/team_fixture.h"

namespace aia {
namespace {

using Team = testing::TeamFixture;

// One robot 1.85 m west of a target's prior mean (sigma 1 m, sensor 2 m, an
// empty 10 x 10 m world).
const char* kOneRobot =
    "workspace: {size: [10.0, 10.0]}\n"
    "robots: {count: 1, start: [[4.25, 5.25]]}\n"
    "targets: {list: [{position: [8.0, 8.0], prior_mean: [6.1, 5.25], "
    "prior_sigma: 1.0}]}\n";

void SetCovariance(Team* team, double sigma) {
  std::vector<Eigen::VectorXd> means;
  std::vector<Eigen::MatrixXd> covs;
  for (const TargetPrior& p : team->world.priors) {
    means.push_back(p.mean);
    covs.push_back(sigma * sigma * Eigen::MatrixXd::Identity(2, 2));
  }
  team->beliefs.SetPrior(means, covs);
}

TEST(SearchMemoryTest, AMissMovesTheAimToTheNearestRingNotRuledOut) {
  Team team(kOneRobot);
  ASSERT_TRUE(team.world.map.lattice().Free(team.positions[0]));
  SearchMemory memory;
  memory.Reset(1, 1);
  const DecisionContext ctx = team.Context();
  memory.Update(ctx, 0);  // the first call only records the belief
  EXPECT_TRUE(memory.Missed(0, 0).empty());
  EXPECT_NEAR((memory.Aim(0, 0) - Vec2(6.1, 5.25)).norm(), 0.0, 1e-12);
  // The robot sees the mean (1.85 m) and the belief did not shrink: its
  // point is missed. Every point of the prior within 2 m of (4.25, 5.25) is
  // ruled out, the mean among them; on the first ring (0.25 sigma) the
  // points at angles 0 and +-45 degrees lie beyond it (2.1 and 2.04 m),
  // each seen from (4.75, 5.25), one lattice step from the robot; the
  // tie goes to angle 0: (6.35, 5.25).
  memory.Update(ctx, 0);
  ASSERT_EQ(memory.Missed(0, 0).size(), 1u);
  EXPECT_EQ(memory.Missed(0, 0)[0], team.positions[0]);
  EXPECT_NEAR(memory.Aim(0, 0).x(), 6.35, 1e-12);
  EXPECT_NEAR(memory.Aim(0, 0).y(), 5.25, 1e-12);
  // The same point again adds nothing; the aim stays.
  memory.Update(ctx, 0);
  EXPECT_EQ(memory.Missed(0, 0).size(), 1u);
  EXPECT_NEAR(memory.Aim(0, 0).x(), 6.35, 1e-12);
  // A belief that shrank (someone measured): the search is over.
  SetCovariance(&team, 0.5);
  memory.Update(team.Context(), 0);
  EXPECT_TRUE(memory.Missed(0, 0).empty());
  EXPECT_NEAR((memory.Aim(0, 0) - Vec2(6.1, 5.25)).norm(), 0.0, 1e-12);
}

TEST(SearchMemoryTest, APointThatDoesNotSeeTheAimMissesNothing) {
  Team team(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 1, start: [[1.25, 1.25]]}\n"
      "targets: {list: [{position: [8.0, 8.0], prior_mean: [6.1, 5.25]}]}\n");
  SearchMemory memory;
  memory.Reset(1, 1);
  for (int step = 0; step < 3; ++step) memory.Update(team.Context(), 0);
  EXPECT_TRUE(memory.Missed(0, 0).empty());
  EXPECT_NEAR((memory.Aim(0, 0) - Vec2(6.1, 5.25)).norm(), 0.0, 1e-12);
}

TEST(SearchMemoryTest, MovingTargetsAreNotSearched) {
  Team team(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 1, start: [[4.25, 5.25]]}\n"
      "targets: {list: [{position: [8.0, 8.0], prior_mean: [6.1, 5.25], "
      "dynamics: {A: [[1.0, 0.0], [0.0, 1.0]], b: [0.0, 0.0], q: 0.01}}]}\n");
  SearchMemory memory;
  memory.Reset(1, 1);
  for (int step = 0; step < 3; ++step) memory.Update(team.Context(), 0);
  EXPECT_TRUE(memory.Missed(0, 0).empty());
}

TEST(SearchMemoryTest,
     RelabellingRobotsPermutesTheMemoryAndTheStepDoesNotEnter) {
  // Robot A sees the mean, robot B (far away) does not. The same team with
  // the labels swapped remembers the same, swapped; the step number given
  // in the context changes nothing.
  const std::string tail =
      "]}\n"
      "targets: {list: [{position: [8.0, 8.0], prior_mean: [6.1, 5.25]}]}\n";
  Team ab(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 2, start: [[4.25, 5.25], [1.25, 1.25]" +
      tail);
  Team ba(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 2, start: [[1.25, 1.25], [4.25, 5.25]" +
      tail);
  SearchMemory mab, mba;
  mab.Reset(2, 1);
  mba.Reset(2, 1);
  for (int step = 0; step < 3; ++step) {
    DecisionContext cab = ab.Context(), cba = ba.Context();
    cab.step = step;
    cba.step = 100 + 7 * step;
    for (int i = 0; i < 2; ++i) {
      mab.Update(cab, i);
      mba.Update(cba, 1 - i);
    }
  }
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(mab.Missed(i, 0), mba.Missed(1 - i, 0)) << "robot " << i;
    EXPECT_EQ(mab.Aim(i, 0), mba.Aim(1 - i, 0)) << "robot " << i;
  }
  EXPECT_EQ(mab.Missed(0, 0).size(), 1u);
  EXPECT_TRUE(mab.Missed(1, 0).empty());
}

}  // namespace
}  // namespace aia
