// robots.model: point (robot_driver.h): a ball on two slide joints (x, y),
// pulled toward its waypoint by a spring; the joints' damping, integrated
// implicitly by MuJoCo, makes it critical.
#include <memory>
#include <vector>

#include "aia/core/check.h"
#include "aia/sim/robot_driver.h"
#include "aia/world/mjcf.h"

namespace aia {
namespace {

class PointDriver : public RobotDriver {
 public:
  PointDriver(const mjModel* m, const std::vector<Vec2>& starts)
      : joints_(m, static_cast<int>(starts.size()), "_x"), starts_(starts) {
    const int kp = mj_name2id(m, mjOBJ_NUMERIC, kKpNumeric);
    AIA_CHECK(kp >= 0 && m->numeric_size[kp] == 1);
    kp_ = m->numeric_data[m->numeric_adr[kp]];
  }

  // The slide joints hold the displacement from the start.
  Vec2 Position(const mjData* d, int i) const override {
    const mjtNum* q = d->qpos + joints_.qpos[i];
    return starts_[i] + Vec2(q[0], q[1]);
  }
  double Heading(const mjData*, int) const override { return 0.0; }
  Vec2 Velocity(const mjData* d, int i) const override {
    return joints_.Velocity(d, i);
  }

  // The spring evaluated as MuJoCo evaluates a position actuator (gain *
  // target + bias * q, with bias = -kp), so that it gives the same numbers.
  void Drive(const std::vector<Vec2>& waypoints, mjData* d,
             std::vector<std::uint8_t>*) const override {
    const int n = static_cast<int>(starts_.size());
    const mjtNum kp = kp_;
    for (int i = 0; i < n; ++i) {
      const int q = joints_.qpos[i], v = joints_.qvel[i];
      const Vec2 target = waypoints[i] - starts_[i];
      for (int c = 0; c < 2; ++c) {
        // MuJoCo's affine bias [0, -kp, 0] . [1, length, velocity].
        mjtNum bias = 0.0 + (-kp) * d->qpos[q + c];
        bias += 0.0 * d->qvel[v + c];
        d->qfrc_applied[v + c] = kp * target[c] + bias;
      }
    }
  }

  double ToGo(const mjData* d, int i, const Vec2& goal) const override {
    return (Position(d, i) - goal).norm();
  }
  bool Slow(const mjData* d, int i, double speed) const override {
    return Velocity(d, i).squaredNorm() <= speed * speed;
  }

  double progress_window() const override { return 0.1; }
  double EnoughProgress(double, double tolerance) const override {
    return tolerance;
  }

 private:
  RobotJoints joints_;
  std::vector<Vec2> starts_;
  double kp_ = 0.0;  // the waypoint spring, as the MJCF states it
};

}  // namespace

std::unique_ptr<const RobotDriver> MakePointDriver(
    const mjModel* m, const Scenario&, const std::vector<Vec2>& starts) {
  return std::make_unique<PointDriver>(m, starts);
}

}  // namespace aia
