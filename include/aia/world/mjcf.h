// MJCF generation (docs/design.md, Physics): floor, border walls, obstacles as
// static bodies, robots as bodies on two damped slide joints (the simulation
// pulls them toward their waypoints with a spring, critically damped),
// targets as collision-free mocap bodies. The file loads in MuJoCo's own
// tools (mujoco-testxml, mujoco-compile, mujoco-simulate).
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

// The targets' spheres, red (the video's legend draws the same colour).
inline constexpr double kTargetRgb[3] = {0.85, 0.1, 0.1};

inline constexpr double kObstacleHeight = 0.5;
inline constexpr double kRobotHalfHeight = 0.05;
inline constexpr double kSensorHeight = 0.05;  // z of sensing rays
inline constexpr char kKpNumeric[] = "aia_kp";

// MuJoCo 2.2 sizes its memory from the model's <size> fields and never grows
// it: an mjData holds njmax x njmax and njmax x nv arrays, and its stack
// must hold the broad phase's nbody^2 / 2 pairs and the Newton solver's
// 3 nv^2. A model is compiled with a first contact budget and the
// simulation grows it when contacts need more (sim/simulation.h).
struct MujocoSizes {
  int nconmax = 0;  // contacts
  int njmax = 0;    // constraint rows
  long nstack = 0;  // stack, in mjtNums
};
// Constraint rows of one contact: condim 3 with a pyramidal friction cone.
inline constexpr int kRowsPerContact = 4;
// The sizes for a contact budget, from the model's counts (nbody includes the
// world body). The stack is the sum of what MuJoCo 2.2's collision,
// constraint and Newton-solver phases take at most (engine_collision_driver.c,
// engine_solver.c), with room to spare.
MujocoSizes MujocoSizesFor(long nbody, long nv, long contacts);
// The first contact budget of a model with this many robots: room for a
// quarter of them touching something, enough for most missions.
long InitialContacts(int num_robots);
// Bytes one mjData takes with these sizes (its arrays, the stack not
// counted: the stack is mostly never touched).
double MujocoDataBytes(const MujocoSizes& sizes, long nv, long nu);

// A distinct colour per robot id (RGB in [0, 1]); shared by MJCF and overlays.
std::array<float, 3> RobotColor(int robot);

// Body names used by the simulator: "robot<i>", "target<k>", "obstacle<b>";
// joints "robot<i>_x" / "robot<i>_y"; the custom numeric kKpNumeric holds
// the waypoint spring's stiffness physics.kp (as written in the file).
// `contacts`: the model's first contact budget (0: InitialContacts).
std::string MakeMjcf(const World& world, const Scenario& scenario,
                     long contacts = 0);

}  // namespace aia

#endif  // AIA_WORLD_MJCF_H_
