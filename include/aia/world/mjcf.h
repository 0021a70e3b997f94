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
// A diff_drive wheel's contact sphere (hidden in MuJoCo's default view, which
// draws the wheel's cylinder instead).
inline constexpr int kGroupWheel = 3;

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
// engine_solver.c), with room to spare: the Newton solver's dense arrays
// take `hessians` nv x nv blocks (kPointHessians where point robots glide
// free of contacts; wheeled robots, always in contact with the floor, use
// kWheeledHessians: measured 5.0 nv^2 at 10 to 160 robots; the CG solver
// none).
inline constexpr int kPointHessians = 3;
inline constexpr int kWheeledHessians = 6;
// `one_row_contacts` of the contacts are frictionless (condim 1: one
// constraint row instead of kRowsPerContact).
MujocoSizes MujocoSizesFor(long nbody, long nv, long contacts,
                           int hessians = kPointHessians,
                           long one_row_contacts = 0);
// Whether a model steps with Newton's method (else CG), and how many nv x nv
// blocks its stack holds for it, from the scenario's physics.solver.
struct SolverChoice {
  bool newton = true;
  int hessians = kPointHessians;
};
SolverChoice ChooseSolver(const Scenario& scenario, long nv);
// What a world's MJCF sizes its memory from: its counts, solver and first
// contact budget (`contacts`; 0: InitialContacts).
struct MujocoModelSizes {
  long nbody = 0, nv = 0;
  SolverChoice solver;
  long one_row_contacts = 0;  // the casters' resting contacts
  MujocoSizes sizes;
};
MujocoModelSizes ModelSizesOf(const World& world, const Scenario& scenario,
                              long contacts = 0);
// The first contact budget of a model with this many robots: room for a
// quarter of them touching something, enough for most missions, plus the
// four floor contacts of each diff_drive robot.
long InitialContacts(int num_robots, RobotModel model = RobotModel::kPoint);

// Time constant of a wheel motor's velocity loop, seconds.
inline constexpr double kWheelLoopSeconds = 0.02;
// What the MJCF of a diff_drive robot is made of, derived from its
// parameters (robots.diff_drive) and the disc's radius.
struct DiffDriveBody {
  double chassis_mass = 0.0;    // kg; each wheel wheel_mass
  double wheel_mass = 0.0;      // kg
  double caster_radius = 0.0;   // m
  double caster_offset = 0.0;   // m ahead of and behind the axle
  double chassis_bottom = 0.0;  // m above the floor
  double wheel_damping = 0.0;   // N m s: the motor's velocity-loop gain
};
DiffDriveBody DiffDriveBodyOf(const DiffDriveConfig& config, double radius);
// The most memory a simulation's MuJoCo arrays may take, as its contacts
// grow and (World::Build refuses a world beyond it) at the start. MuJoCo
// 2.2 holds them in one buffer whose size is an int (mjData::nbuffer): past
// 2 GiB it cannot make the mjData at all (775 wheeled robots compile, 800
// do not, where MujocoDataBytes says 1.95 and 2.08 GiB); 1.9 GiB leaves
// room for the arrays it does not count.
inline constexpr double kMaxPhysicsBytes = 1.9 * (1L << 30);
// Bytes one mjData takes with these sizes (its arrays, the stack not
// counted: the stack is mostly never touched).
double MujocoDataBytes(const MujocoSizes& sizes, long nv, long nu);

// A distinct colour per robot id (RGB in [0, 1]); shared by MJCF and overlays.
std::array<float, 3> RobotColor(int robot);

// Body names used by the simulator: "robot<i>", "target<k>", "obstacle<b>";
// point robots: joints "robot<i>_x" / "robot<i>_y", and the custom numeric
// kKpNumeric holds the waypoint spring's stiffness physics.kp (as written in
// the file); diff_drive robots: the free joint "robot<i>_root", wheel bodies
// and hinge joints "robot<i>_left" / "robot<i>_right", the chassis geom
// "robot<i>_chassis".
// `contacts`: the model's first contact budget (0: InitialContacts).
// Throws InputError (CheckNumericLocale) under a comma-decimal locale.
std::string MakeMjcf(const World& world, const Scenario& scenario,
                     long contacts = 0);

// Throws InputError("locale", 0, "LC_NUMERIC", ...) unless the C library
// writes and reads numbers with a decimal point (the "C" numeric locale, or
// any with '.'): MuJoCo's model reader and aia's writers follow it.
void CheckNumericLocale();

}  // namespace aia

#endif  // AIA_WORLD_MJCF_H_
