// The robot models' drivers (sim/robot_driver.h), each by hand: where its
// joints put the robot, the forces its controller applies, and how its
// progress is measured.
#include "aia/sim/robot_driver.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "aia/sim/simulation.h"
#include "aia/world/world.h"
#include "support/test_support.h"

namespace aia {
namespace {

using testing::ScenarioFromYaml;

struct Rig {
  explicit Rig(const std::string& model)
      : scenario(ScenarioFromYaml(
            "robots: {count: 2, start: [[5.25, 5.25], [6.25, 5.25]], model: " +
            model + "}\ntargets: {list: [{position: [19, 19]}]}\n")),
        world(World::Build(scenario)),
        physics(world, scenario),
        data(mj_makeData(physics.model())),
        starts{{5.25, 5.25}, {6.25, 5.25}},
        driver(MakeRobotDriver(physics.model(), scenario, starts)) {
    mj_forward(physics.model(), data.get());
  }
  Scenario scenario;
  World world;
  PhysicsModel physics;
  MjDataPtr data;
  std::vector<Vec2> starts;
  std::unique_ptr<const RobotDriver> driver;
};

TEST(RobotDriverTest, PointRobotsAreSpringsOnTwoSlides) {
  Rig rig("point");
  const RobotDriver& d = *rig.driver;
  // At rest at their starts: the slides hold the displacement.
  EXPECT_EQ(d.Position(rig.data.get(), 1), Vec2(6.25, 5.25));
  EXPECT_EQ(d.Heading(rig.data.get(), 1), 0.0);
  EXPECT_EQ(d.Velocity(rig.data.get(), 1), Vec2(0.0, 0.0));
  // A waypoint 0.5 m along +x pulls with kp * 0.5 along x alone.
  const double kp = rig.scenario.physics.kp;
  std::vector<std::uint8_t> turning(2, 0);
  d.Drive({{5.25, 5.25}, {6.75, 5.25}}, rig.data.get(), &turning);
  const int x = mj_name2id(rig.physics.model(), mjOBJ_JOINT, "robot1_x");
  const int v = rig.physics.model()->jnt_dofadr[x];
  EXPECT_DOUBLE_EQ(rig.data->qfrc_applied[v], kp * 0.5);
  EXPECT_EQ(rig.data->qfrc_applied[v + 1], 0.0);
  EXPECT_EQ(turning, (std::vector<std::uint8_t>{0, 0}));
  // Progress: the distance, the tolerance in 0.1 s.
  EXPECT_DOUBLE_EQ(d.ToGo(rig.data.get(), 1, {6.25, 5.75}), 0.5);
  EXPECT_TRUE(d.Slow(rig.data.get(), 1, 0.01));
  EXPECT_EQ(d.progress_window(), 0.1);
  EXPECT_EQ(d.EnoughProgress(0.03, 0.01), 0.01);
}

TEST(RobotDriverTest, WheeledRobotsTurnAndMeasureWheelTravel) {
  Rig rig("diff_drive, diff_drive: {start_heading: 0}");
  const RobotDriver& d = *rig.driver;
  // A free joint at the start, facing +x.
  EXPECT_LT((d.Position(rig.data.get(), 0) - Vec2(5.25, 5.25)).norm(), 1e-9);
  EXPECT_NEAR(d.Heading(rig.data.get(), 0), 0.0, 1e-12);
  // A waypoint straight behind needs no turn when it may reverse (the
  // default): wheel travel is the distance; one to the side is a quarter
  // turn first, each wheel rolling half_track * pi / 2 more, turning in
  // place.
  const double half_track = 0.5 * rig.scenario.robots.diff_drive.track;
  EXPECT_NEAR(d.ToGo(rig.data.get(), 0, {4.75, 5.25}), 0.5, 1e-9);
  EXPECT_NEAR(d.ToGo(rig.data.get(), 0, {5.25, 5.75}),
              0.5 + half_track * M_PI / 2, 1e-9);
  std::vector<std::uint8_t> turning(2, 0);
  d.Drive({{5.25, 5.75}, {6.25, 5.25}}, rig.data.get(), &turning);
  EXPECT_EQ(turning, (std::vector<std::uint8_t>{1, 0}));
  // Progress: a longer window; near the goal a quarter of what is left
  // beyond the tolerance.
  EXPECT_EQ(d.progress_window(), 0.25);
  EXPECT_DOUBLE_EQ(d.EnoughProgress(0.03, 0.01), 0.005);
  EXPECT_DOUBLE_EQ(d.EnoughProgress(0.5, 0.01), 0.01);
  EXPECT_EQ(d.EnoughProgress(0.005, 0.01), 0.0);
}

}  // namespace
}  // namespace aia
