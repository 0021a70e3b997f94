#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

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
  EXPECT_EQ(sim.model()->nconmax, InitialContacts(7));
  EXPECT_EQ(sim.model()->njmax, kRowsPerContact * InitialContacts(7));
  // The broad phase's pairs and the Newton solver's Hessians fit the stack.
  const long nbody = sim.model()->nbody, nv = sim.model()->nv;
  EXPECT_EQ(nv, 14);
  EXPECT_GE(sim.model()->nstack, nbody * (nbody - 1) / 2 + 3 * nv * nv);
  EXPECT_EQ(sim.model()->nu, 0);  // the waypoint spring is applied by aia
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

// A step that times out lasts step_timeout / timestep substeps: 0.56 s is
// 112 of 0.005 s (the quotient, 112.00000000000001, took 113).
TEST(SimulationTest, ATimedOutStepLastsTheTimeoutsSubsteps) {
  const Scenario s = ScenarioFromYaml(
      "workspace: {size: [20, 20]}\n"
      "robots: {count: 1, start: [[1.25, 5.25]]}\n"
      "targets: {count: 1}\n"
      "physics: {kp: 50, step_timeout: 0.56}\n");
  const World w = World::Build(s);
  Simulation sim(w, s);
  sim.SetWaypoint(0, {10.25, 5.25});  // 9 m: about 0.67 s of the spring
  const PhysicsStepStats st = sim.AdvanceToWaypoints();
  EXPECT_TRUE(st.timed_out);
  EXPECT_EQ(st.substeps, 112);
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

// A failed robot (lockstep): a teammate pushes it off its waypoint, and the
// step neither waits for it nor counts it stalled or late (it counted
// stalls for a robot that had failed, and steps waited for it).
TEST(SimulationTest, ARetiredRobotIsNeitherWaitedForNorCounted) {
  const Scenario s = ScenarioFromYaml(
      "robots: {count: 2, start: [[5.25, 5.25], [6.25, 5.25]]}\ntargets: "
      "{count: 1}\n");
  const World w = World::Build(s);
  Simulation sim(w, s);
  sim.Retire(1);
  sim.SetWaypoint(0, {6.25, 5.25});  // onto the failed robot's place
  sim.SetWaypoint(1, {6.25, 5.25});
  const PhysicsStepStats st = sim.AdvanceToWaypoints();
  EXPECT_FALSE(st.all_arrived);
  EXPECT_EQ(st.stalled + st.late, 1);  // robot 0 alone
  EXPECT_EQ(sim.robot_stalls()[1] + sim.robot_timeouts()[1], 0);
  EXPECT_EQ(sim.robot_stalls()[0] + sim.robot_timeouts()[0], 1);
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

// A target exactly at a robot (a listed target on its start; a moving target
// onto a resting robot) is in sight: nothing lies between a point and
// itself. mj_ray refuses so short a ray, which ended the run with
// "MuJoCo: mj_ray: vector length is too small".
TEST(SensingTest, ATargetAtTheRobotIsInSight) {
  const Scenario s = WallScenario();
  const World w = World::Build(s);
  Simulation sim(w, s);
  const Vec2 p = sim.RobotPosition(0);
  EXPECT_TRUE(sim.RayClear(p, p));
  EXPECT_TRUE(sim.RayClear(p, p + Vec2(1e-17, 0.0)));
  SensorModel sensor;
  std::vector<Rng> rngs = {Rng(1, "s", 0)};
  std::vector<std::vector<Measurement>> z;
  Sense(sim, sensor, {p}, {p}, {1}, &rngs, &z);
  ASSERT_EQ(z[0].size(), 1u);
  EXPECT_EQ(z[0][0].target, 0);
  EXPECT_NEAR(z[0][0].y.norm(), 0.0, 0.1);  // noise of std 0.01 at 0 m
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

// mj_ray itself, as RayClear was before its index: the answer the index
// must give on every segment of the workspace, where a border wall can
// only be met at an end (and is not between the points).
bool MjRayClear(const Simulation& sim, const Vec2& from, const Vec2& to) {
  const mjtNum pnt[3] = {from.x(), from.y(), kSensorHeight};
  const mjtNum vec[3] = {to.x() - from.x(), to.y() - from.y(), 0.0};
  mjtByte groups[mjNGROUP] = {0};
  groups[kGroupObstacle] = 1;
  int geom = -1;
  const mjtNum x =
      mj_ray(sim.model(), sim.data(), pnt, vec, groups, 1, -1, &geom);
  if (geom >= 0) {
    const char* body =
        mj_id2name(sim.model(), mjOBJ_BODY, sim.model()->geom_bodyid[geom]);
    if (body && std::string(body).rfind("wall", 0) == 0) return true;
  }
  return x < 0.0 || x >= 1.0;
}

// A target exactly on the workspace's border is in sight of a robot that
// sees it across open floor: the ray ends on a border wall's inner face
// (placed at the size printed to 6 digits), which is not between the two.
// It was never measured in workspaces 7, 7.5, 7.7 or 12.3 m high, and was
// in 8 or 10 m (rounding), while the world's own check called it
// measurable. Every side, and a corner.
TEST(SensingTest, ATargetOnTheBorderIsInSight) {
  for (const double side : {7.0, 7.5, 7.7, 12.3, 10.0}) {
    const std::string size = std::to_string(side);
    const Scenario s = ScenarioFromYaml(
        "workspace: {size: [" + size + ", " + size +
        "], obstacles: {random: {count: 0}}}\nrobots: {count: 1, start: "
        "[[3.25, 3.25]]}\ntargets: {count: 1}\n");
    const World w = World::Build(s);
    Simulation sim(w, s);
    const double c = side / 2;
    for (const Vec2& target : {Vec2(c, side), Vec2(side, c), Vec2(c, 0.0),
                               Vec2(0.0, c), Vec2(side, side)}) {
      const Vec2 robot = target + 1.5 * (Vec2(c, c) - target).normalized();
      EXPECT_TRUE(sim.RayClear(robot, target))
          << side << ": " << target.transpose();
      EXPECT_TRUE(w.map.LineOfSight(robot, target));
      EXPECT_EQ(sim.RayClear(robot, target), MjRayClear(sim, robot, target));
    }
  }
}

TEST(SensingTest, RayClearIsMjRayInClutterMazesAndRooms) {
  // Random segments of up to 4 m, and segments from box corners and edge
  // midpoints (grazing hits), in a cluttered world and generated maps.
  for (const char* extra :
       {"workspace: {size: [30, 30], obstacles: {random: {count: 90}}}\n",
        "workspace: {size: [30, 30], obstacles: {generator: {type: maze}}}\n",
        "workspace: {size: [30, 30], obstacles: {generator: {type: "
        "rooms}}}\n"}) {
    const Scenario s = ScenarioFromYaml(
        std::string("robots: {count: 4}\ntargets: {count: 4}\n") + extra);
    const World w = World::Build(s);
    Simulation sim(w, s);
    Rng rng(17);
    int blocked = 0, trials = 0;
    const auto check = [&](const Vec2& a, const Vec2& b) {
      if ((a - b).norm() < 1e-6) return;  // mj_ray refuses (clamped ends)
      const bool clear = sim.RayClear(a, b);
      ASSERT_EQ(clear, MjRayClear(sim, a, b))
          << extra << a.transpose() << " -> " << b.transpose();
      blocked += !clear;
      ++trials;
    };
    // Segments of the workspace, as the sensor's are: from a robot (inside)
    // to a target (on the border at most).
    const auto inside = [](const Vec2& p, double margin = 0.0) {
      return Vec2(std::clamp(p.x(), margin, 30.0 - margin),
                  std::clamp(p.y(), margin, 30.0 - margin));
    };
    const double kIn = 1e-3;
    for (int t = 0; t < 3000; ++t) {
      const Vec2 a(rng.Uniform(-1.0, 31.0), rng.Uniform(-1.0, 31.0));
      const double r = rng.Uniform(0.0, 4.0), th = rng.Uniform(0.0, 6.3);
      check(inside(a, kIn), inside(a + r * Vec2(std::cos(th), std::sin(th))));
    }
    for (const Box& box : w.map.obstacles()) {
      for (const Vec2& p :
           {box.lo, box.hi, Vec2(box.lo.x(), box.hi.y()),
            Vec2(box.hi.x(), box.lo.y()), Vec2(box.Center().x(), box.lo.y()),
            Vec2(box.lo.x(), box.Center().y())}) {
        const double th = rng.Uniform(0.0, 6.3);
        check(inside(p + 2.0 * Vec2(std::cos(th), std::sin(th)), kIn), p);
        check(inside(p - Vec2(1.5, 0.0), kIn), inside(p + Vec2(1.5, 0.0)));
        check(inside(p - Vec2(0.0, 1.5), kIn), inside(p + Vec2(0.0, 1.5)));
      }
    }
    // Both answers occur (the test can tell a wrong index).
    EXPECT_GT(blocked, trials / 20) << extra;
    EXPECT_LT(blocked, trials - trials / 20) << extra;
  }
}

TEST(MujocoHandlersTest, ErrorsAreExceptionsAndWarningsAreKept) {
  InstallMujocoHandlers();
  const bool had_log = std::filesystem::exists("MUJOCO_LOG.TXT");
  ::testing::internal::CaptureStdout();
  EXPECT_THROW(mju_error("a test error"), PhysicsError);
  try {
    mju_error("a test error");
  } catch (const PhysicsError& e) {
    EXPECT_STREQ(e.what(), "MuJoCo: a test error");
  }
  mju_warning("a test warning");
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");  // MuJoCo prints
  EXPECT_EQ(LastMujocoWarning(), "a test warning");
  // MuJoCo's own handlers append to MUJOCO_LOG.TXT in the working folder.
  EXPECT_EQ(std::filesystem::exists("MUJOCO_LOG.TXT"), had_log);
}

// The resets of an unstable state are the bad_* warnings alone (a contact
// overflow is handled and says nothing of the motion), counted by type.
TEST(MujocoHandlersTest, UnstableStateReportNamesTheResets) {
  std::array<long, mjNWARNING> w{};
  EXPECT_EQ(UnstableStateReport(w), "");
  w[mjWARN_CONTACTFULL] = 3;
  w[mjWARN_INERTIA] = 1;
  EXPECT_EQ(UnstableStateReport(w), "");
  w[mjWARN_BADQACC] = 1;
  EXPECT_EQ(UnstableStateReport(w),
            "MuJoCo reset an unstable state 1 time (bad_qacc 1)");
  w[mjWARN_BADQPOS] = 2;
  w[mjWARN_BADCTRL] = 4;
  EXPECT_EQ(UnstableStateReport(w),
            "MuJoCo reset an unstable state 7 times (bad_qpos 2, bad_qacc 1, "
            "bad_ctrl 4)");
  // The line the commands print: the mission named, the report, what to
  // change; nothing when no state was reset.
  // What to change names the keys of the robots' model only.
  EXPECT_EQ(UnstableStateWarning(w, RobotModel::kDiffDrive, "m, seed 3"),
            "warning: m, seed 3: " + UnstableStateReport(w) +
                ": the robots' motion after it is not physical (too strong a "
                "motor for its mass and time step: lower "
                "robots.diff_drive.max_torque, raise robots.diff_drive.mass "
                "or lower physics.timestep)\n");
  EXPECT_EQ(UnstableStateWarning(w, RobotModel::kPoint, "m"),
            "warning: m: " + UnstableStateReport(w) +
                ": the robots' motion after it is not physical (too strong a "
                "motor for its mass and time step: lower physics.kp, raise "
                "physics.robot_mass or lower physics.timestep)\n");
  EXPECT_EQ(UnstableStateWarning({}, RobotModel::kPoint, "m, seed 3"), "");
}

// A mission of no motion: every move ended at the timeout or stalled, and no
// lattice move was completed. Counts by hand: 2 robots x 3 moves, 4
// timeouts and 2 stalls.
TEST(MujocoHandlersTest, NoArrivalWarningOnlyWhenNoRobotArrived) {
  EXPECT_EQ(NoArrivalWarning({3, 3}, {3, 1}, {0, 2}, 0, "w, seed 3"),
            "warning: w, seed 3: no robot reached the lattice point it drove "
            "to in 6 moves (4 ended at physics.step_timeout, 2 stalled): the "
            "robots block each other or the walls, or cannot move with these "
            "settings (raise "
            "physics.step_timeout, or for wheeled robots "
            "robots.diff_drive.max_speed, max_turn_rate or the gains, or "
            "lower robots.diff_drive.mass)\n");
  // One robot arrived once (a lattice move, or a move short of both).
  EXPECT_EQ(NoArrivalWarning({3, 3}, {3, 1}, {0, 2}, 1, "w"), "");
  EXPECT_EQ(NoArrivalWarning({3, 3}, {3, 1}, {0, 1}, 0, "w"), "");
  // Nobody was sent anywhere (success at step 0, every robot failed, or
  // every decision a stay or a wait for a held point).
  EXPECT_EQ(NoArrivalWarning({0, 0}, {0, 0}, {0, 0}, 0, "w"), "");
}

TEST(MujocoHandlersTest, AStackOverflowInsideMjStepIsAPhysicsError) {
  // 40 bodies whose broad phase needs 780 pairs of stack: 100 is too few
  // (set after compiling: the compiler steps the model once itself).
  std::string xml = "<mujoco><worldbody>";
  for (int i = 0; i < 40; ++i)
    xml += "<body pos=\"" + std::to_string(i) +
           " 0 0\"><freejoint/><geom size=\"0.1\"/></body>";
  xml += "</worldbody></mujoco>";
  MjModelPtr model = CompileMjcf(xml);
  model->nstack = 100;
  MjDataPtr data(mj_makeData(model.get()));
  EXPECT_THROW(mj_step(model.get(), data.get()), PhysicsError);
}

// A crowd: discs of radius 0.24 on a 0.5 m lattice, every point but a few
// taken, so that moving robots push into their neighbours.
Scenario CrowdScenario(int robots, double side) {
  return ScenarioFromYaml("workspace: {size: [" + std::to_string(side) + ", " +
                          std::to_string(side) +
                          "], obstacles: {random: {count: 0}}}\n"
                          "robots: {count: " +
                          std::to_string(robots) +
                          ", radius: 0.24}\ntargets: {count: 1}\n");
}

// Drives every robot one lattice step in a seeded random direction.
void PushCrowd(const World& w, Simulation* sim, Rng* rng) {
  const Lattice& lattice = w.map.lattice();
  for (int i = 0; i < sim->num_robots(); ++i) {
    const int at = lattice.NearestFree(sim->RobotPosition(i));
    const Move m = static_cast<Move>(rng->UniformInt(kNumMoves));
    const int next = lattice.Valid(at, m) ? lattice.Next(at, m) : at;
    sim->SetWaypoint(i, lattice.Point(next));
  }
}

TEST(SimulationTest, ContactBudgetGrowsWithoutChangingResults) {
  const Scenario s = CrowdScenario(60, 4.0);
  const World w = World::Build(s);
  // One model starts with room for a single contact, the other with room
  // for every contact the crowd can make.
  Simulation small(std::make_shared<const PhysicsModel>(w, s, 1));
  Simulation large(std::make_shared<const PhysicsModel>(w, s, 2000));
  EXPECT_EQ(small.model()->nconmax, 1);
  Rng a(5), b(5);
  for (int step = 0; step < 4; ++step) {
    PushCrowd(w, &small, &a);
    PushCrowd(w, &large, &b);
    const PhysicsStepStats x = small.AdvanceToWaypoints();
    const PhysicsStepStats y = large.AdvanceToWaypoints();
    ASSERT_EQ(x.substeps, y.substeps);
    for (int i = 0; i < s.robots.count; ++i) {
      ASSERT_EQ(small.RobotPosition(i).x(), large.RobotPosition(i).x());
      ASSERT_EQ(small.RobotPosition(i).y(), large.RobotPosition(i).y());
    }
  }
  EXPECT_GT(small.memory().grows, 0);
  EXPECT_GT(small.model()->nconmax, 1);
  EXPECT_EQ(large.memory().grows, 0);
  EXPECT_GT(large.memory().max_contacts, 10);
  for (long count : small.warnings()) EXPECT_EQ(count, 0);
  // The stack held what the broad phase and the solver took.
  EXPECT_LT(small.memory().max_stack, small.memory().nstack);
}

TEST(SimulationTest, ACrowdOf250StaysApart) {
  const Scenario s = CrowdScenario(250, 8.0);
  const World w = World::Build(s);
  Simulation sim(w, s);
  Rng rng(11);
  for (int step = 0; step < 3; ++step) {
    PushCrowd(w, &sim, &rng);
    sim.AdvanceToWaypoints();
  }
  EXPECT_GT(sim.memory().max_contacts, InitialContacts(250));
  for (long count : sim.warnings()) EXPECT_EQ(count, 0);
  // Contacts are soft: a robot may sink into another by a few millimetres.
  double closest = 1e9;
  for (int i = 0; i < 250; ++i)
    for (int j = i + 1; j < 250; ++j)
      closest = std::min(closest,
                         (sim.RobotPosition(i) - sim.RobotPosition(j)).norm());
  EXPECT_GT(closest, 2 * 0.24 - 0.02);
}

}  // namespace
}  // namespace aia
