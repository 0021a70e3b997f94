// One class per robot model (robots.model), as MuJoCo MPC keeps its tasks
// apart: what the simulation needs to know of how robots of that model move
// (which MuJoCo joints hold their pose, the low-level controller that drives
// them toward their waypoints before every mj_step, and how their progress
// is measured). Simulation (simulation.h) holds one and never asks which
// model it is. A driver belongs to the compiled model (PhysicsModel) and is
// shared, read-only, by every simulation of it: what changes is in the
// mjData it is given.
//
// The models (one file each, listed in MakeRobotDriver, robot_driver.cc):
//   point       point_driver.cc: a ball on two slide joints, pulled toward
//               its waypoint by a spring;
//   diff_drive  diff_drive_driver.cc: a wheeled base on a free joint, its
//               wheels driven by the law of diff_drive.h.
#ifndef AIA_SIM_ROBOT_DRIVER_H_
#define AIA_SIM_ROBOT_DRIVER_H_

#include <mujoco/mujoco.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "aia/core/types.h"
#include "aia/scenario/config.h"

namespace aia {

class RobotDriver {
 public:
  virtual ~RobotDriver() = default;

  // Robot i's position in the world frame, and its heading (radians from
  // +x; 0 for a model without one).
  virtual Vec2 Position(const mjData* d, int i) const = 0;
  virtual double Heading(const mjData* d, int i) const = 0;
  // Robot i's velocity in the plane.
  virtual Vec2 Velocity(const mjData* d, int i) const = 0;

  // The controllers' forces for the next mj_step (d->qfrc_applied), each
  // robot toward its waypoint; (*turning)[i] is set when robot i turns in
  // place (never for a model that does not turn).
  virtual void Drive(const std::vector<Vec2>& waypoints, mjData* d,
                     std::vector<std::uint8_t>* turning) const = 0;

  // How far robot i still has to go to `goal` (its progress is measured in
  // it), and whether it moves no faster than `speed`.
  virtual double ToGo(const mjData* d, int i, const Vec2& goal) const = 0;
  virtual bool Slow(const mjData* d, int i, double speed) const = 0;

  // A robot is stuck when ToGo has not shrunk by EnoughProgress(before, the
  // tolerance) over progress_window() seconds, `before` being its ToGo at
  // the start of the window.
  virtual double progress_window() const = 0;
  virtual double EnoughProgress(double before, double tolerance) const = 0;
  // Seconds robot i needs to brake what it still rolls with from its last
  // move (0 for a model whose moves start from rest): a new move's stall
  // test waits that long, since a robot that reverses passes through rest
  // and first goes the wrong way.
  virtual double BrakeSeconds(const mjData*, int) const { return 0.0; }
};

// Per robot: the qpos and qvel addresses of the joint "robotI" + `suffix`
// that holds its position (x, y first).
struct RobotJoints {
  RobotJoints(const mjModel* m, int robots, const std::string& suffix);

  Vec2 Velocity(const mjData* d, int i) const {
    const mjtNum* v = d->qvel + qvel[i];
    return {v[0], v[1]};
  }

  std::vector<int> qpos, qvel;
};

// The driver of scenario.robots.model for the robots of a compiled model
// (MakeMjcf's bodies and joints), starting at `starts`.
std::unique_ptr<const RobotDriver> MakeRobotDriver(
    const mjModel* m, const Scenario& scenario,
    const std::vector<Vec2>& starts);

// The models' own (robot_driver.cc lists them).
std::unique_ptr<const RobotDriver> MakePointDriver(
    const mjModel* m, const Scenario& scenario,
    const std::vector<Vec2>& starts);
std::unique_ptr<const RobotDriver> MakeDiffDriveDriver(
    const mjModel* m, const Scenario& scenario,
    const std::vector<Vec2>& starts);

// The joint `name` of a compiled model (AIA_CHECK that it exists).
int RobotJoint(const mjModel* m, const std::string& name);

}  // namespace aia

#endif  // AIA_SIM_ROBOT_DRIVER_H_
