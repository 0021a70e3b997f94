// robots.model: diff_drive (robot_driver.h): a wheeled base on a free joint
// (x, y, z, quaternion; linear then angular velocity), its two wheels'
// motors following the speeds of the controller in diff_drive.h.
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "aia/sim/diff_drive.h"
#include "aia/sim/robot_driver.h"

namespace aia {
namespace {

constexpr double kEnoughTurnProgress = 0.01;  // m per progress window

class DiffDriveDriver : public RobotDriver {
 public:
  DiffDriveDriver(const mjModel* m, const Scenario& scenario, int robots)
      : joints_(m, robots, "_root"),
        max_torque_(scenario.robots.diff_drive.max_torque),
        law_(scenario.robots.diff_drive, scenario.physics.tolerance) {
    for (int i = 0; i < robots; ++i) {
      const std::string robot = "robot" + std::to_string(i);
      wheel_dof_.push_back({m->jnt_dofadr[RobotJoint(m, robot + "_left")],
                            m->jnt_dofadr[RobotJoint(m, robot + "_right")]});
    }
    wheel_kv_ = robots > 0 ? m->dof_damping[wheel_dof_[0][0]] : 0.0;
  }

  // A free joint holds the body's position in the world frame.
  Vec2 Position(const mjData* d, int i) const override {
    const mjtNum* q = d->qpos + joints_.qpos[i];
    return {q[0], q[1]};
  }
  double Heading(const mjData* d, int i) const override {
    return YawOf(d->qpos + joints_.qpos[i] + 3);
  }
  Vec2 Velocity(const mjData* d, int i) const override {
    return joints_.Velocity(d, i);
  }

  // Each robot's controller sets its wheels' speeds; the motors' velocity
  // loops (the wheels' damping, implicit in MuJoCo, plus this drive torque)
  // follow them within their torque limit.
  void Drive(const std::vector<Vec2>& waypoints, mjData* d,
             std::vector<std::uint8_t>* turning) const override {
    const int n = static_cast<int>(wheel_dof_.size());
    for (int i = 0; i < n; ++i) {
      const WheelSpeeds w =
          law_.Control(Position(d, i), Heading(d, i), waypoints[i]);
      (*turning)[i] = w.turning ? 1 : 0;
      const int left = wheel_dof_[i][0], right = wheel_dof_[i][1];
      d->qfrc_applied[left] =
          MotorTorque(wheel_kv_, w.left, d->qvel[left], max_torque_);
      d->qfrc_applied[right] =
          MotorTorque(wheel_kv_, w.right, d->qvel[right], max_torque_);
    }
  }

  // The wheel travel left, turning included, and the rim speed.
  double ToGo(const mjData* d, int i, const Vec2& goal) const override {
    return law_.ToGo(Position(d, i), Heading(d, i), goal);
  }
  bool Slow(const mjData* d, int i, double speed) const override {
    // The free joint's angular velocity is in the body's frame: z is the
    // turn rate while the robot stands upright.
    const double turn = d->qvel[joints_.qvel[i] + 5];
    return Velocity(d, i).norm() + std::fabs(turn) * law_.half_track() <= speed;
  }

  // A wheeled robot starts from rest and may first turn in place: its
  // window is longer, and on its last centimetres, where its speed fades
  // with the distance, a quarter of what is left beyond the tolerance is
  // progress enough.
  double progress_window() const override { return 0.25; }
  // A robot declared arrived within the tolerance still rolls at about
  // speed_gain x tolerance (0.2 m/s at 0.025 m), and its next move may
  // point the other way.
  double BrakeSeconds(const mjData* d, int i) const override {
    const double turn = d->qvel[joints_.qvel[i] + 5];
    return (Velocity(d, i).norm() + std::fabs(turn) * law_.half_track()) /
           law_.brake();
  }
  // At most 1 cm (the default tolerance's) whatever the tolerance: a robot
  // turning in place toward its goal gains half_track x the heading it
  // turns, a few centimetres a window as the heading error closes.
  double EnoughProgress(double before, double tolerance) const override {
    return std::min({tolerance, 0.25 * std::max(0.0, before - tolerance),
                     kEnoughTurnProgress});
  }

 private:
  RobotJoints joints_;
  // Each robot's left and right wheel dof, the motors' velocity loop gain
  // (the wheels' damping, as the MJCF states it) and torque limit.
  std::vector<std::array<int, 2>> wheel_dof_;
  double wheel_kv_ = 0.0;
  double max_torque_ = 0.0;
  DiffDriveLaw law_;
};

}  // namespace

std::unique_ptr<const RobotDriver> MakeDiffDriveDriver(
    const mjModel* m, const Scenario& scenario,
    const std::vector<Vec2>& starts) {
  return std::make_unique<DiffDriveDriver>(m, scenario,
                                           static_cast<int>(starts.size()));
}

}  // namespace aia
