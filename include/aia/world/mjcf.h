// MJCF generation (docs/design.md, Physics): floor, border walls, obstacles as
// static bodies, robots as bodies on two slide joints driven by position
// actuators (critically damped), targets as collision-free mocap bodies. The
// file loads in MuJoCo's own tools (mujoco-testxml, mujoco-compile,
// mujoco-simulate).
#ifndef AIA_WORLD_MJCF_H_
#define AIA_WORLD_MJCF_H_

#include <array>
#include <string>

#include "aia/scenario/config.h"
#include "aia/world/world.h"

namespace aia {

// Geom groups, so that sensing rays see obstacles only.
inline constexpr int kGroupFloor = 0;
inline constexpr int kGroupObstacle = 1;
inline constexpr int kGroupAgent = 2;  // robots and targets

inline constexpr double kObstacleHeight = 0.5;
inline constexpr double kRobotHalfHeight = 0.05;
inline constexpr double kSensorHeight = 0.05;  // z of sensing rays

// A distinct colour per robot id (RGB in [0, 1]); shared by MJCF and overlays.
std::array<float, 3> RobotColor(int robot);

// Body names used by the simulator: "robot<i>", "target<k>", "obstacle<b>";
// joints "robot<i>_x" / "robot<i>_y"; actuators likewise.
std::string MakeMjcf(const World& world, const Scenario& scenario);

}  // namespace aia

#endif  // AIA_WORLD_MJCF_H_
