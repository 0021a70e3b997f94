// The differential-drive robot (robots.model: diff_drive): its controller's
// law worked out by hand, then the body in MuJoCo: it reaches each lattice
// neighbour from any heading, stays upright, never passes through a wall or
// another robot, and steps the same way every time.
#include "aia/sim/diff_drive.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "aia/sim/simulation.h"
#include "aia/world/mjcf.h"
#include "support/test_support.h"

namespace aia {
namespace {

using testing::ScenarioFromYaml;

constexpr double kDeg = kPi / 180.0;

TEST(DiffDriveLawTest, AnglesAndQuaternions) {
  EXPECT_NEAR(WrapAngle(1.5 * kPi), -0.5 * kPi, 1e-12);
  EXPECT_NEAR(WrapAngle(-kPi), kPi, 1e-12);  // (-pi, pi]
  EXPECT_NEAR(WrapAngle(0.1 - 4 * kPi), 0.1, 1e-12);
  // 30 degrees about z: (cos 15, 0, 0, sin 15).
  const double q[4] = {std::cos(15 * kDeg), 0.0, 0.0, std::sin(15 * kDeg)};
  EXPECT_NEAR(YawOf(q), 30 * kDeg, 1e-12);
  const double back[4] = {0.0, 0.0, 0.0, 1.0};  // 180 degrees
  EXPECT_NEAR(std::fabs(YawOf(back)), kPi, 1e-12);
}

// Kobuki's defaults: r = 0.035, track 0.23, v_max 0.7 m/s, 180 deg/s,
// torque 0.12 N m on 2.35 kg (braking a = 0.12 / (0.035 * 2.35) = 1.459 m/s^2),
// gains 8 and 4, drive angle 20 degrees; tolerance 0.01 (stop within 2.5 mm).
TEST(DiffDriveLawTest, WheelSpeedsWorkedOutByHand) {
  const DiffDriveConfig c;
  const DiffDriveLaw law(c, 0.01);
  const Vec2 o(5.0, 5.0);
  // Far ahead: full speed on both wheels, 0.7 / 0.035 = 20 rad/s.
  WheelSpeeds w = law.Control(o, 0.0, {7.0, 5.0});
  EXPECT_NEAR(w.left, 20.0, 1e-9);
  EXPECT_NEAR(w.right, 20.0, 1e-9);
  // 60 degrees to the left: beyond the drive angle, so it turns in place at
  // the capped rate pi rad/s (4 * 1.047 > pi): rims at pi * 0.115 m/s, the
  // right wheel forward.
  w = law.Control(o, 0.0,
                  o + 2.0 * Vec2(std::cos(60 * kDeg), std::sin(60 * kDeg)));
  EXPECT_NEAR(w.right, kPi * 0.115 / 0.035, 1e-9);
  EXPECT_NEAR(w.left, -kPi * 0.115 / 0.035, 1e-9);
  // Straight behind: it reverses, no turn.
  w = law.Control(o, 0.0, {3.0, 5.0});
  EXPECT_NEAR(w.left, -20.0, 1e-9);
  EXPECT_NEAR(w.right, -20.0, 1e-9);
  // 10 degrees off: omega = 4 * 10 deg = 0.698 rad/s, rim 0.0803 m/s;
  // fade (cos 10 - cos 20) / (1 - cos 20) = 0.7481, so v = min(0.7, 16,
  // sqrt(2 * 1.459 * 2)) * 0.7481 = 0.5237, below 0.7 - 0.0803.
  const double a = 10 * kDeg;
  w = law.Control(o, 0.0, o + 2.0 * Vec2(std::cos(a), std::sin(a)));
  const double fade =
      (std::cos(a) - std::cos(20 * kDeg)) / (1.0 - std::cos(20 * kDeg));
  const double v = 0.7 * fade, turn = 4.0 * a * 0.115;
  EXPECT_NEAR(w.left, (v - turn) / 0.035, 1e-9);
  EXPECT_NEAR(w.right, (v + turn) / 0.035, 1e-9);
  // 5 cm ahead: braking caps the speed, sqrt(2 * 1.459 * 0.05) = 0.3820
  // (the distance's 8 * 0.05 = 0.4 is more).
  const double brake = 0.12 / (0.035 * 2.35);
  w = law.Control(o, 0.0, {5.05, 5.0});
  EXPECT_NEAR(w.left, std::sqrt(2.0 * brake * 0.05) / 0.035, 1e-9);
  // 2 cm ahead: the distance's 8 * 0.02 = 0.16 m/s.
  w = law.Control(o, 0.0, {5.02, 5.0});
  EXPECT_NEAR(w.right, 0.16 / 0.035, 1e-9);
  // Within a quarter of the tolerance: stopped.
  w = law.Control(o, 1.0, {5.002, 5.0});
  EXPECT_EQ(w.left, 0.0);
  EXPECT_EQ(w.right, 0.0);
}

TEST(DiffDriveLawTest, WithoutReverseTheRobotTurnsAround) {
  DiffDriveConfig c;
  c.reverse = false;
  const DiffDriveLaw law(c, 0.01);
  bool backward = true;
  EXPECT_NEAR(std::fabs(law.HeadingError({5, 5}, 0.0, {3, 5}, &backward)), kPi,
              1e-12);
  EXPECT_FALSE(backward);
  const WheelSpeeds w = law.Control({5, 5}, 0.0, {3, 5});
  EXPECT_NEAR(std::fabs(w.left), kPi * 0.115 / 0.035, 1e-9);
  EXPECT_NEAR(w.left, -w.right, 1e-12);
  // Travel left: 2 m and half a turn at 0.115 m of arm.
  EXPECT_NEAR(law.ToGo({5, 5}, 0.0, {3, 5}), 2.0 + 0.115 * kPi, 1e-12);
}

TEST(DiffDriveLawTest, MotorTorqueStaysWithinItsLimit) {
  // kv 0.07 N m s: asking 20 rad/s from rest saturates at +0.12 N m of
  // drive beyond the damping's -kv * omega (0 at rest).
  EXPECT_NEAR(MotorTorque(0.07, 20.0, 0.0, 0.12), 0.12, 1e-12);
  // Near the speed asked for, the drive is kv * omega_ref = 1.4, its net
  // with the damping 0.07 * (20 - 19.5) = 0.035 within the limit.
  EXPECT_NEAR(MotorTorque(0.07, 20.0, 19.5, 0.12), 1.4, 1e-12);
  // Braking hard from 20 rad/s to 0: net -0.12.
  EXPECT_NEAR(MotorTorque(0.07, 0.0, 20.0, 0.12), 1.4 - 0.12, 1e-12);
}

// One or more wheeled robots at given starts (lattice points) and headings.
Scenario WheeledScenario(const std::string& starts, double heading_deg,
                         const std::string& extra = "",
                         const std::string& diff_drive = "") {
  char yaml[800];
  std::snprintf(
      yaml, sizeof(yaml),
      "robots: {count: %d, start: %s, model: diff_drive, "
      "diff_drive: {%sstart_heading: %g}}\n"
      "targets: {list: [{position: [19, 19]}]}\n%s",
      static_cast<int>(std::count(starts.begin(), starts.end(), '[')) - 1,
      starts.c_str(), diff_drive.c_str(), heading_deg, extra.c_str());
  return ScenarioFromYaml(yaml);
}

// The body's up axis (its z in the world): 1 when level.
double Upright(const Simulation& sim, int i) {
  const int root = mj_name2id(sim.model(), mjOBJ_JOINT,
                              ("robot" + std::to_string(i) + "_root").c_str());
  const double* q = sim.data()->qpos + sim.model()->jnt_qposadr[root] + 3;
  // z of the rotated z axis: 1 - 2 (x^2 + y^2).
  return 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2]);
}

TEST(DiffDriveTest, ModelHasWheelsOnHingesAndNoActuators) {
  const Scenario s = WheeledScenario("[[5.25, 5.25], [6.25, 5.25]]", 0.0);
  const World w = World::Build(s);
  Simulation sim(w, s);
  // Per robot: a free joint (6) and two wheel hinges; three bodies.
  EXPECT_EQ(sim.model()->nv, 16);
  EXPECT_EQ(sim.model()->nu, 0);  // the motors' torques are applied by aia
  EXPECT_EQ(sim.model()->opt.gravity[2], -9.81);
  for (const char* joint : {"robot0_left", "robot0_right", "robot1_left"}) {
    const int j = mj_name2id(sim.model(), mjOBJ_JOINT, joint);
    ASSERT_GE(j, 0) << joint;
    EXPECT_EQ(sim.model()->jnt_type[j], mjJNT_HINGE);
    EXPECT_GT(sim.model()->dof_damping[sim.model()->jnt_dofadr[j]], 0.0);
  }
  // It rests on the floor at its start, level, facing +x.
  for (int k = 0; k < 100; ++k) sim.StepPhysics();
  EXPECT_LT((sim.RobotPosition(0) - Vec2(5.25, 5.25)).norm(), 1e-3);
  EXPECT_NEAR(sim.RobotHeading(0), 0.0, 1e-3);
  EXPECT_GT(Upright(sim, 0), std::cos(1.0 * kDeg));
  EXPECT_GE(sim.data()->ncon, 8);  // two wheels and two casters each
}

TEST(DiffDriveTest, ReachesEachNeighbourFromAnyHeading) {
  const Vec2 start(5.25, 5.25);
  for (int heading = -180; heading < 180; heading += 30) {
    for (const Vec2& offset :
         {Vec2(0.5, 0), Vec2(-0.5, 0), Vec2(0, 0.5), Vec2(0, -0.5)}) {
      const Scenario s = WheeledScenario("[[5.25, 5.25]]", heading);
      const World w = World::Build(s);
      Simulation sim(w, s);
      EXPECT_NEAR(WrapAngle(sim.RobotHeading(0) - heading * kDeg), 0.0, 1e-6);
      sim.SetWaypoint(0, start + offset);
      double min_upright = 1.0;
      const PhysicsStepStats st = sim.AdvanceToWaypoints([&](double) {
        min_upright = std::min(min_upright, Upright(sim, 0));
      });
      SCOPED_TRACE("heading " + std::to_string(heading) + ", to " +
                   std::to_string(offset.x()) + ", " +
                   std::to_string(offset.y()));
      EXPECT_TRUE(st.all_arrived);
      EXPECT_FALSE(st.timed_out);
      EXPECT_EQ(st.stalled, 0);
      EXPECT_LE((sim.RobotPosition(0) - (start + offset)).norm(),
                s.physics.tolerance);
      EXPECT_GT(min_upright, std::cos(5.0 * kDeg));
      // Driving takes time: at least 0.5 m at 0.7 m/s.
      EXPECT_GT(st.substeps * s.physics.timestep, 0.5 / 0.7);
    }
  }
}

TEST(DiffDriveTest, ATourOfStepsEndsWhereItShould) {
  // A square and back, each step from the heading the last one left.
  const Scenario s = WheeledScenario("[[5.25, 5.25]]", 37.0);
  const World w = World::Build(s);
  Simulation sim(w, s);
  Vec2 at(5.25, 5.25);
  for (const Vec2& d : {Vec2(0.5, 0), Vec2(0, 0.5), Vec2(-0.5, 0),
                        Vec2(0, -0.5), Vec2(0, -0.5), Vec2(0.5, 0)}) {
    at += d;
    sim.SetWaypoint(0, at);
    const PhysicsStepStats st = sim.AdvanceToWaypoints();
    EXPECT_TRUE(st.all_arrived);
    EXPECT_LE((sim.RobotPosition(0) - at).norm(), s.physics.tolerance);
  }
  EXPECT_EQ(sim.robot_stalls()[0], 0);
  EXPECT_EQ(sim.robot_timeouts()[0], 0);
}

TEST(DiffDriveTest, NeverPassesThroughAWall) {
  // A wall 0.2 m thick at x 5.6..5.8, the robot sent 1 m beyond it, head on
  // and at 45 degrees: it stops at the face, stalled, not timed out.
  for (const double heading : {0.0, 45.0}) {
    const Scenario s = WheeledScenario(
        "[[5.25, 5.25]]", heading,
        "workspace: {obstacles: {boxes: [{center: [5.7, 5.25], size: [0.2, "
        "3.0]}]}}\n");
    const World w = World::Build(s);
    Simulation sim(w, s);
    sim.SetWaypoint(0, {6.75, 5.25});
    double max_x = 0.0;
    const PhysicsStepStats st = sim.AdvanceToWaypoints(
        [&](double) { max_x = std::max(max_x, sim.RobotPosition(0).x()); });
    EXPECT_FALSE(st.all_arrived);
    EXPECT_FALSE(st.timed_out);
    EXPECT_EQ(st.stalled, 1);
    EXPECT_EQ(sim.robot_stalls()[0], 1);
    // The disc's edge stays at the face (5.6), within MuJoCo's soft contact.
    EXPECT_LT(max_x, 5.6 - 0.15 + 0.01);
    EXPECT_GT(Upright(sim, 0), std::cos(5.0 * kDeg));
  }
}

TEST(DiffDriveTest, HeadOnCollisionKeepsBothUprightAndApart) {
  // Two robots facing each other 1.5 m apart (robot 1 first turns around:
  // no reversing), then each sent 1.5 m through the other.
  const Scenario s = WheeledScenario("[[5.25, 5.25], [7.25, 5.25]]", 0.0, "",
                                     "reverse: false, ");
  const World w = World::Build(s);
  Simulation sim(w, s);
  sim.SetWaypoint(1, {6.75, 5.25});
  ASSERT_TRUE(sim.AdvanceToWaypoints().all_arrived);
  ASSERT_NEAR(std::fabs(sim.RobotHeading(1)), kPi, 0.1);
  sim.SetWaypoint(0, {6.75, 5.25});
  sim.SetWaypoint(1, {5.25, 5.25});
  double min_gap = 1e9, min_upright = 1.0, max_z = 0.0, closing = 0.0;
  const PhysicsStepStats st = sim.AdvanceToWaypoints([&](double) {
    min_gap =
        std::min(min_gap, (sim.RobotPosition(0) - sim.RobotPosition(1)).norm());
    min_upright = std::min({min_upright, Upright(sim, 0), Upright(sim, 1)});
    max_z = std::max(max_z, sim.data()->qpos[2]);
    closing =
        std::max(closing, sim.RobotVelocity(0).x() - sim.RobotVelocity(1).x());
  });
  EXPECT_FALSE(st.all_arrived);
  EXPECT_EQ(st.stalled, 2);             // blocked by each other
  EXPECT_GT(closing, 1.0);              // they met at speed
  EXPECT_GT(min_gap, 2 * 0.15 - 0.02);  // discs never pass through
  EXPECT_GT(min_upright, std::cos(10.0 * kDeg));
  EXPECT_LT(max_z, 0.035 + 0.02);  // the wheels stay on the floor
}

TEST(DiffDriveTest, StepsAreTheSameEveryTime) {
  const Scenario s =
      WheeledScenario("[[5.25, 5.25], [6.25, 5.25], [5.25, 6.25]]", 90.0);
  const World w = World::Build(s);
  auto run = [&] {
    Simulation sim(w, s);
    std::vector<double> out;
    const std::vector<std::vector<Vec2>> plan = {
        {{5.75, 5.25}, {6.25, 5.75}, {5.25, 6.75}},
        {{5.75, 5.75}, {6.25, 6.25}, {4.75, 6.75}}};
    for (const auto& step : plan) {
      for (int i = 0; i < 3; ++i) sim.SetWaypoint(i, step[i]);
      out.push_back(sim.AdvanceToWaypoints().substeps);
      for (int q = 0; q < sim.model()->nq; ++q)
        out.push_back(sim.data()->qpos[q]);
    }
    return out;
  };
  const std::vector<double> a = run(), b = run();
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a[k], b[k]) << k;
}

TEST(DiffDriveTest, SolverIsNewtonUntilItsArraysGrowTooLarge) {
  Scenario s = WheeledScenario("[[5.25, 5.25]]", 0.0);
  // 6 nv^2 doubles within 256 MiB: nv up to 2364.
  EXPECT_TRUE(ChooseSolver(s, 8 * 80).newton);
  EXPECT_EQ(ChooseSolver(s, 8 * 80).hessians, kWheeledHessians);
  EXPECT_FALSE(ChooseSolver(s, 8 * 500).newton);
  EXPECT_EQ(ChooseSolver(s, 8 * 500).hessians, 0);
  s.physics.solver = PhysicsSolver::kNewton;
  EXPECT_TRUE(ChooseSolver(s, 8 * 500).newton);
  s.physics.solver = PhysicsSolver::kCg;
  EXPECT_FALSE(ChooseSolver(s, 8 * 10).newton);
  // Point robots keep MuJoCo's default (their MJCF names no solver).
  s.robots.model = RobotModel::kPoint;
  s.physics.solver = PhysicsSolver::kAuto;
  EXPECT_TRUE(ChooseSolver(s, 2 * 1000).newton);
  EXPECT_EQ(ChooseSolver(s, 2 * 1000).hessians, kPointHessians);
}

}  // namespace
}  // namespace aia
