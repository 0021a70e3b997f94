#include "aia/estimation/team_estimate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace aia {
namespace {

using Measurements = std::vector<std::vector<Measurement>>;

// Two robots, one static target at the prior N((1, 1), 4 I): Omega_0 = 0.25 I.
TeamEstimate TwoRobots() {
  return TeamEstimate({TargetModel::Static(2)}, 2, {Eigen::Vector2d(1.0, 1.0)},
                      {Eigen::MatrixXd::Identity(2, 2) * 4.0});
}

// Robot 0 at the origin measures the target at (3, 1) with precision 0.75;
// robot 1 measures nothing.
Measurements RobotZeroMeasures() {
  Measurements z(2);
  z[0].push_back({0, Vec2(3.0, 1.0), 0.75});
  return z;
}

const std::vector<Vec2> kAtOrigin = {Vec2(0.0, 0.0), Vec2(5.0, 5.0)};
const std::vector<std::uint8_t> kBothActive = {1, 1};

// An unstable target (A = 2 I): the variance of an estimate no measurement
// reaches grows 4 times a step and passes kMaxVariance (1e24) at step 40.
// The mission ended there even while another robot measured the target
// every step (a failed robot's own belief, or a cut-off one's). It ends only
// when every active robot's estimate has passed the bound; the others stay
// at it.
TEST(TeamEstimateTest, OnlyEveryActiveEstimateDivergingIsADivergence) {
  TargetModel unstable = TargetModel::Static(2);
  unstable.A = 2.0 * Eigen::MatrixXd::Identity(2, 2);
  const auto team = [&] {
    return TeamEstimate({unstable}, 2, {Eigen::Vector2d(1.0, 1.0)},
                        {Eigen::MatrixXd::Identity(2, 2)});
  };
  const std::vector<std::vector<int>> apart = {{}, {}};
  for (const std::vector<std::uint8_t>& active :
       {kBothActive, std::vector<std::uint8_t>{1, 0}}) {
    TeamEstimate e = team();
    for (int step = 0; step < 80; ++step)
      e.Update(step > 0, apart, 0.5, RobotZeroMeasures(), kAtOrigin, active);
    // Robot 0's precision per axis settles where w = w / 4 + 0.75: w = 1.
    EXPECT_NEAR(e.Det(0, 0), 1.0, 1e-9);
    EXPECT_TRUE(std::isfinite(e.Det(1, 0)));
    EXPECT_GT(e.Det(1, 0), 1e40);  // at the bound: (1e24)^2 scaled back
  }
  // Nobody measures: the team's estimate diverges, at step 40.
  TeamEstimate e = team();
  int step = 0;
  try {
    for (; step < 80; ++step)
      e.Update(step > 0, apart, 0.5, Measurements(2), kAtOrigin, kBothActive);
    ADD_FAILURE() << "no divergence";
  } catch (const EstimateDiverged& d) {
    EXPECT_EQ(d.target(), 0);
  }
  EXPECT_EQ(step, 40);
}

TEST(TeamEstimateTest, PriorIsEveryRowsBeliefAndItsLogDetIsKept) {
  const TeamEstimate e = TwoRobots();
  EXPECT_EQ(e.num_robots(), 2);
  EXPECT_EQ(e.num_targets(), 1);
  ASSERT_EQ(e.log_det_prior().size(), 1u);
  EXPECT_NEAR(e.log_det_prior()[0], std::log(16.0), 1e-12);
  EXPECT_NEAR(e.fused().DetCovariance(1, 0), 16.0, 1e-12);
  EXPECT_NEAR(e.central().DetCovariance(0, 0), 16.0, 1e-12);
}

// Isolated robots (W = I): robot 0's Omega is 0.25 + 0.75 = 1, so Sigma = I
// (det 1) and mu = Sigma (0.25 (1, 1) + 0.75 ((3, 1) + 0)) = (2.5, 1); robot
// 1 keeps the prior (det 16). The centralized row has the same measurement.
TEST(TeamEstimateTest, IsolatedRobotsFuseOnlyTheirOwnMeasurements) {
  TeamEstimate e = TwoRobots();
  e.Update(false, {{}, {}}, 0.5, RobotZeroMeasures(), kAtOrigin, kBothActive);
  EXPECT_NEAR(e.Det(0, 0), 1.0, 1e-12);
  EXPECT_NEAR(e.Det(1, 0), 16.0, 1e-12);
  EXPECT_NEAR(e.fused().PositionMean(0, 0).x(), 2.5, 1e-12);
  EXPECT_NEAR(e.fused().PositionMean(0, 0).y(), 1.0, 1e-12);
  EXPECT_NEAR(e.central().PositionMean(0, 0).x(), 2.5, 1e-12);
  EXPECT_NEAR(e.central().DetCovariance(0, 0), 1.0, 1e-12);
  EXPECT_EQ(e.BestRobot(0), 0);
  EXPECT_NEAR(e.MinDet(0), 1.0, 1e-12);
  EXPECT_EQ(e.NumLocalized(1.0), 1);
  EXPECT_EQ(e.NumLocalized(0.5), 0);
}

// Connected with kappa_self 0.5 (W = all 0.5): at step 0 each row mixes two
// priors (Omega 0.25) and robot 0 adds its measurement (Omega 1). At step 1
// (static target: the prediction is the identity) both rows average 1 and
// 0.25: Omega 0.625, det Sigma = 1 / 0.625^2 = 2.56; the tie goes to the
// lower index.
TEST(TeamEstimateTest, NeighboursAverageTheirInformationWithTheDkfWeights) {
  TeamEstimate e = TwoRobots();
  const std::vector<std::vector<int>> graph = {{1}, {0}};
  e.Update(false, graph, 0.5, RobotZeroMeasures(), kAtOrigin, kBothActive);
  EXPECT_NEAR(e.Det(0, 0), 1.0, 1e-12);
  EXPECT_NEAR(e.Det(1, 0), 16.0, 1e-12);
  e.Update(true, graph, 0.5, Measurements(2), kAtOrigin, kBothActive);
  EXPECT_NEAR(e.Det(0, 0), 2.56, 1e-12);
  EXPECT_NEAR(e.Det(1, 0), 2.56, 1e-12);
  EXPECT_EQ(e.BestRobot(0), 0);
}

TEST(TeamEstimateTest, OnlyActiveRobotsHoldTheTeamsBestEstimate) {
  TeamEstimate e = TwoRobots();
  e.Update(false, {{}, {}}, 0.5, RobotZeroMeasures(), kAtOrigin, {0, 1});
  EXPECT_EQ(e.BestRobot(0), 1);
  EXPECT_NEAR(e.MinDet(0), 16.0, 1e-12);
  e.Update(true, {{}, {}}, 0.5, Measurements(2), kAtOrigin, {0, 0});
  EXPECT_EQ(e.BestRobot(0), -1);
  EXPECT_EQ(e.MinDet(0), std::numeric_limits<double>::infinity());
  EXPECT_EQ(e.NumLocalized(1e9), 0);
}

}  // namespace
}  // namespace aia
