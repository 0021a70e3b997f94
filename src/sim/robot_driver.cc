// The robot models' list (robot_driver.h) and what they share.
#include "aia/sim/robot_driver.h"

#include "aia/core/check.h"

namespace aia {

int RobotJoint(const mjModel* m, const std::string& name) {
  const int j = mj_name2id(m, mjOBJ_JOINT, name.c_str());
  AIA_CHECK(j >= 0);
  return j;
}

RobotJoints::RobotJoints(const mjModel* m, int robots,
                         const std::string& suffix) {
  for (int i = 0; i < robots; ++i) {
    const int j = RobotJoint(m, "robot" + std::to_string(i) + suffix);
    qpos.push_back(m->jnt_qposadr[j]);
    qvel.push_back(m->jnt_dofadr[j]);
  }
}

std::unique_ptr<const RobotDriver> MakeRobotDriver(
    const mjModel* m, const Scenario& scenario,
    const std::vector<Vec2>& starts) {
  switch (scenario.robots.model) {
    case RobotModel::kPoint:
      return MakePointDriver(m, scenario, starts);
    case RobotModel::kDiffDrive:
      return MakeDiffDriveDriver(m, scenario, starts);
  }
  AIA_CHECK_MSG(false, "a robot model without a driver");
  return nullptr;
}

}  // namespace aia
