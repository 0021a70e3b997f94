#include <gtest/gtest.h>

#include "aia/sim/simulation.h"
#include "aia/world/mjcf.h"
#include "support/test_support.h"

namespace aia {
namespace {

using testing::ScenarioFromYaml;

// Two robots, a wall between x = 4.5 and 5.5, targets: one behind the wall,
// one in the open within range, one out of range.
Scenario WallScenario() {
  return ScenarioFromYaml(
      "robots:\n  count: 2\n  start: [[3.75, 5.25], [3.75, 12.25]]\n"
      "targets:\n  list:\n"
      "    - {position: [6.0, 5.25]}\n"    // 2.25 m away, behind the wall
      "    - {position: [5.25, 12.25]}\n"  // 1.5 m away, in the open
      "    - {position: [3.75, 15.0]}\n"   // 2.75 m from robot 1: out of range
      "    - {position: [5.25, 5.25]}\n"  // 1.5 m, inside?  no: beside the wall
      "workspace: {obstacles: {boxes: [{center: [4.9, 5.0], size: [0.4, "
      "4.0]}]}}\n");
}

TEST(SimulationTest, ModelIsSizedFromTheRobotCount) {
  const Scenario s =
      ScenarioFromYaml("robots: {count: 7}\ntargets: {count: 2}\n");
  const World w = World::Build(s);
  Simulation sim(w, s);
  EXPECT_EQ(sim.model()->njmax, 8 * 7 + 500);
  EXPECT_EQ(sim.model()->nconmax, 2 * 7 + 100);
  EXPECT_EQ(sim.model()->nu, 14);
  EXPECT_EQ(sim.model()->nmocap, 2);
  for (int i = 0; i < 7; ++i)
    EXPECT_LT((sim.RobotPosition(i) - w.map.lattice().Point(w.robot_starts[i]))
                  .norm(),
              1e-9);
}

TEST(SimulationTest, RobotTracksItsWaypoint) {
  const Scenario s = ScenarioFromYaml(
      "robots: {count: 1, start: [[5.25, 5.25]]}\n"
      "targets: {count: 1}\n");
  const World w = World::Build(s);
  Simulation sim(w, s);
  sim.SetWaypoint(0, {5.75, 5.25});
  const PhysicsStepStats st = sim.AdvanceToWaypoints();
  EXPECT_TRUE(st.all_arrived);
  EXPECT_FALSE(st.timed_out);
  EXPECT_LT((sim.RobotPosition(0) - Vec2(5.75, 5.25)).norm(),
            s.physics.tolerance);
}

TEST(SimulationTest, ContactsKeepRobotsApart) {
  // Both robots are sent to the same point: real contacts stop them short.
  const Scenario s = ScenarioFromYaml(
      "robots: {count: 2, start: [[5.25, 5.25], [6.25, 5.25]]}\ntargets: "
      "{count: 1}\n");
  const World w = World::Build(s);
  Simulation sim(w, s);
  sim.SetWaypoint(0, {5.75, 5.25});
  sim.SetWaypoint(1, {5.75, 5.25});
  const PhysicsStepStats st = sim.AdvanceToWaypoints();
  EXPECT_FALSE(st.all_arrived);
  EXPECT_GT((sim.RobotPosition(0) - sim.RobotPosition(1)).norm(),
            2 * 0.15 - 0.02);
}

TEST(SimulationTest, RobotDoesNotPassThroughAnObstacle) {
  const Scenario s = ScenarioFromYaml(
      "robots: {count: 1, start: [[4.25, 5.25]]}\ntargets: {count: 1}\n"
      "workspace: {obstacles: {boxes: [{center: [5.0, 5.25], size: [0.4, "
      "2.0]}]}}\n");
  const World w = World::Build(s);
  Simulation sim(w, s);
  sim.SetWaypoint(0, {5.75, 5.25});  // beyond the box: the world rule forbids
  sim.AdvanceToWaypoints();          // this, but physics must hold anyway
  EXPECT_LT(sim.RobotPosition(0).x(), 4.8 - 0.15 + 0.02);
}

TEST(SensingTest, WallBlocksAndOpenSpaceSees) {
  const Scenario s = WallScenario();
  const World w = World::Build(s);
  Simulation sim(w, s);
  SensorModel sensor;  // range 2, line of sight on
  std::vector<Vec2> robots = {sim.RobotPosition(0), sim.RobotPosition(1)};
  std::vector<Vec2> targets;
  for (int k = 0; k < 4; ++k) targets.push_back(sim.TargetPosition(k));
  std::vector<Rng> rngs = {Rng(1, "s", 0), Rng(1, "s", 1)};
  std::vector<std::vector<Measurement>> z;
  Sense(sim, sensor, robots, targets, {1, 1}, &rngs, &z);
  ASSERT_EQ(z.size(), 2u);
  // Robot 0 sees nothing: target 0 is behind the wall, target 3 is beyond its
  // near face too (the box spans x 4.7..5.1).
  EXPECT_TRUE(z[0].empty());
  ASSERT_EQ(z[1].size(), 1u);
  EXPECT_EQ(z[1][0].target, 1);
  // y = pos_k - p_i + v with small noise (std 0.01 + 0.05 * 1.5 = 0.085).
  EXPECT_NEAR(z[1][0].y.x(), 1.5, 0.5);
  EXPECT_NEAR(z[1][0].y.y(), 0.0, 0.5);
  EXPECT_NEAR(z[1][0].precision, sensor.Precision(z[1][0].y.norm()), 1e-12);
  // Without line of sight the walled target in range is seen.
  sensor.line_of_sight = false;
  Sense(sim, sensor, robots, targets, {1, 1}, &rngs, &z);
  EXPECT_EQ(z[0].size(), 1u);  // target 3 (1.5 m); target 0 is 2.25 m away
  // An inactive robot senses nothing.
  Sense(sim, sensor, robots, targets, {1, 0}, &rngs, &z);
  EXPECT_TRUE(z[1].empty());
}

TEST(SensingTest, RayClearMatchesWorldLineOfSight) {
  const Scenario s = WallScenario();
  const World w = World::Build(s);
  Simulation sim(w, s);
  Rng rng(9);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec2 a(rng.Uniform(0.5, 9.5), rng.Uniform(0.5, 9.5));
    const Vec2 b(rng.Uniform(0.5, 9.5), rng.Uniform(0.5, 9.5));
    EXPECT_EQ(sim.RayClear(a, b), w.map.LineOfSight(a, b))
        << a.transpose() << " -> " << b.transpose();
  }
}

}  // namespace
}  // namespace aia
