// The physics of a mission (docs/design.md, Physics): a MuJoCo model generated
// from the world, robots that track lattice waypoints (a spring applied before
// every mj_step, damped by the joints) and real contacts, targets as mocap
// bodies, and ray sensing against obstacles. No process-wide MuJoCo callbacks:
// the caller sets waypoints and this class calls mj_step explicitly.
#ifndef AIA_SIM_SIMULATION_H_
#define AIA_SIM_SIMULATION_H_

#include <mujoco/mujoco.h>

#include <array>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "aia/core/box_buckets.h"
#include "aia/core/point_grid.h"
#include "aia/core/rng.h"
#include "aia/core/types.h"
#include "aia/estimation/sensor_model.h"
#include "aia/scenario/config.h"
#include "aia/sim/robot_driver.h"
#include "aia/world/mjcf.h"
#include "aia/world/world.h"

namespace aia {

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using MjModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;
using MjDataPtr = std::unique_ptr<mjData, MjDataDeleter>;

// An error MuJoCo raised (mju_error): one line, thrown through MuJoCo's C
// frames (libmujoco has unwind tables). The mjData it came from is left in an
// unknown state and must not be stepped again.
class PhysicsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Replaces MuJoCo's process-wide error and warning handlers, once: its own
// print to stdout, append to MUJOCO_LOG.TXT in the working folder and, for an
// error, wait for Enter on stdin and exit. Errors become PhysicsError;
// warnings are counted per mjData (mjData::warning), which the simulation
// reports, so the handler keeps only this thread's last message.
// Called by everything here that runs MuJoCo; safe to call again.
void InstallMujocoHandlers();
// The name of a MuJoCo warning type (mjtWarning), e.g. "bad_qacc".
const char* MujocoWarningName(int warning);
// This thread's last MuJoCo warning message ("" if none).
const std::string& LastMujocoWarning();
// Where MuJoCo found the state unstable and reset it (the bad_qpos,
// bad_qvel, bad_qacc and bad_ctrl warnings among `warnings`, counted by
// type): "" if never, else one sentence naming the counts, e.g. "MuJoCo
// reset an unstable state 2 times (bad_qacc 2)". The motion after such a
// reset is not physical, so a command warns with it.
std::string UnstableStateReport(const std::array<long, mjNWARNING>& warnings);
// The line a command prints on stderr after a mission whose state MuJoCo
// reset, "warning: WHAT: REPORT: the robots' motion after it is not
// physical (...what to change for robots of `model`)\n" (`what` names the
// mission); "" if none.
std::string UnstableStateWarning(const std::array<long, mjNWARNING>& warnings,
                                 RobotModel model, const std::string& what);
// The line a command prints on stderr after a mission in which no robot
// ever reached the lattice point it drove to: `moves` lattice moves were
// completed (0), and every one of the robots' `drives` (moves sent to
// another lattice point; stays and waits for a held point are none) ended
// at the step timeout or stalled (`timeouts`, `stalls`: per robot, summed).
// Such settings make a mission of no motion (motors too slow or a timeout too
// short for them; point robots are refused ahead, wheeled ones cannot be,
// since their motion depends on the contacts and turns they meet). "" when
// some robot arrived, or none was asked to move.
std::string NoArrivalWarning(const std::vector<long>& drives,
                             const std::vector<long>& timeouts,
                             const std::vector<long>& stalls, long moves,
                             const std::string& what);

// Compiles MJCF text (through MuJoCo's virtual file system); throws
// std::runtime_error with MuJoCo's message if it does not compile.
MjModelPtr CompileMjcf(const std::string& xml);

struct PhysicsStepStats {
  int substeps = 0;  // mj_step calls
  bool all_arrived = false;
  bool timed_out = false;  // the step timeout passed first
  int stalled = 0;         // robots that ended short of their waypoint, blocked
  int late = 0;            // robots still on their way at the timeout
};

// How a simulation's MuJoCo memory went (diagnostics.json).
struct PhysicsMemoryStats {
  int nconmax = 0;          // contact budget now
  int njmax = 0;            // constraint rows now
  int grows = 0;            // times the budget was doubled
  int max_contacts = 0;     // most contacts in one mj_step
  int max_constraints = 0;  // most constraint rows in one mj_step
  long max_stack = 0;       // most stack used (mjtNums) of nstack
  long nstack = 0;
  double data_bytes = 0.0;  // the mjData's arrays
};

// The compiled MuJoCo model of a world: generated once per instance and
// shared, read-only, by every simulation of it (mj_step takes the model as
// const), so that the runs of several policies on one world compile it once.
class PhysicsModel {
 public:
  // Generates the world's MJCF and compiles it; throws std::runtime_error
  // with MuJoCo's message if it does not compile.
  // `contacts`: the first contact budget (0: InitialContacts); results do
  // not depend on it.
  PhysicsModel(const World& world, const Scenario& scenario, long contacts = 0);

  const mjModel* model() const { return model_.get(); }
  const std::string& mjcf() const { return mjcf_; }
  const PhysicsConfig& physics() const { return physics_; }
  RobotModel robot_model() const { return robot_model_; }
  int num_robots() const { return static_cast<int>(starts_.size()); }
  int num_targets() const { return static_cast<int>(mocap_id_.size()); }

 private:
  friend class Simulation;
  std::string mjcf_;
  MjModelPtr model_;
  PhysicsConfig physics_;
  RobotModel robot_model_ = RobotModel::kPoint;
  // What MujocoSizesFor sizes a grown budget with: the stack's Newton
  // blocks and the resting one-row contacts.
  int hessians_ = kPointHessians;
  long one_row_contacts_ = 0;
  std::vector<Vec2> starts_;
  // How the robots of the model move (robot_driver.h).
  std::unique_ptr<const RobotDriver> driver_;
  std::vector<int> mocap_id_;
};

// One simulation of a model: its own mjData, stepped explicitly.
class Simulation {
 public:
  explicit Simulation(std::shared_ptr<const PhysicsModel> model);
  // Compiles a model of its own.
  Simulation(const World& world, const Scenario& scenario);

  int num_robots() const { return model_->num_robots(); }
  int num_targets() const { return model_->num_targets(); }
  // The model being stepped: the shared one, or this simulation's copy once
  // its contact budget has grown (the same bodies, larger buffers).
  const mjModel* model() const { return m_; }
  mjData* data() { return data_.get(); }
  const mjData* data() const { return data_.get(); }
  const std::string& mjcf() const { return model_->mjcf(); }

  RobotModel robot_model() const { return model_->robot_model(); }
  Vec2 RobotPosition(int i) const;
  Vec2 RobotVelocity(int i) const;
  // Radians from +x (a point robot's is always 0).
  double RobotHeading(int i) const;
  void SetWaypoint(int i, const Vec2& p);
  Vec2 TargetPosition(int k) const;
  void SetTargetPosition(int k, const Vec2& p);

  // Runs mj_step until every robot is within the tolerance of its waypoint,
  // or every robot that has not arrived has stalled (blocked by a contact:
  // slower than 1 cm/s, or closer to its waypoint by less than the tolerance
  // than 0.1 s before; a diff_drive robot's speed is its wheels' rim speed
  // and its closeness the wheel travel left, turning included), or the step
  // timeout passes.
  // `on_substep(elapsed_seconds)` runs after each mj_step (targets' mocap
  // interpolation, video frames).
  PhysicsStepStats AdvanceToWaypoints(
      const std::function<void(double)>& on_substep = {});

  // Whether the segment between two points at sensor height meets no obstacle
  // (mj_ray against the obstacle geom group only). The same answer as
  // mj_ray, which in MuJoCo 2.2 visits every geom, from the geoms whose
  // bounds meet the segment's: the obstacle geoms in buckets, each tested
  // with mju_rayGeom as mj_ray tests it (mj_ray itself where a geom of the
  // group is not a static primitive). The four border walls lie outside the
  // workspace and are not tested: a segment from a point inside the
  // workspace to one in it can only touch their inner faces at its end,
  // where a target on the border is (the workspace's own line of sight,
  // Map::LineOfSight, has no walls either).
  bool RayClear(const Vec2& from, const Vec2& to) const;

  // One mj_step. When the contacts of the step overflow MuJoCo's budget
  // (it would drop them: robots would pass through each other), the step is
  // undone, the budget doubled and the step taken again, so that results
  // never depend on the budget. Throws PhysicsError for MuJoCo's errors and
  // std::runtime_error when the contacts need more memory than
  // kMaxPhysicsBytes.
  void StepPhysics();

  // Asynchronous decisions (mission.decisions: async): each robot's move
  // runs on its own clock. StartMove sends robot i to `p` from now (its
  // stall and timeout clocks start now); Hold keeps it at its waypoint (a
  // stay) until the simulation clock reaches `until` substeps; Park keeps it
  // there until its next move (a failed robot, for good).
  void StartMove(int i, const Vec2& p);
  // `yielding`: it waits for a point another robot holds (its time counts
  // as yielding, not staying).
  void Hold(int i, long until, bool yielding = false);
  void Park(int i);
  // Runs mj_step until some robot's move or hold ends, or until the clock
  // reaches `until` substeps. Robots whose moves ended go to `ended`
  // (ascending): arrived within the tolerance, stalled (blocked, as
  // AdvanceToWaypoints tells it, on the robot's own clock; counted in the
  // stats and robot_stalls), timed out (likewise), or held to `until` of
  // their Hold; a robot then stays parked until it is given a new move.
  // `on_substep` as in AdvanceToWaypoints, with the clock's seconds.
  PhysicsStepStats AdvanceMoves(long until, std::vector<int>* ended,
                                const std::function<void(double)>& on_substep);
  // mj_step calls so far, and the clock in seconds (substeps x timestep).
  long clock() const { return clock_; }
  double clock_seconds() const { return clock_ * m_->opt.timestep; }

  // A failed robot, in lockstep: it keeps driving to its waypoint (it holds
  // its place where others push it), but a decision step neither waits for
  // it nor counts it stalled or late (AdvanceToWaypoints).
  void Retire(int i) { retired_[i] = 1; }

  // Per robot: decision steps that ended with it stalled short of its
  // waypoint, and those whose timeout found it still on its way.
  const std::vector<long>& robot_stalls() const { return robot_stalls_; }
  const std::vector<long>& robot_timeouts() const { return robot_timeouts_; }
  // Where the robots' simulated time went, robot-seconds summed over the
  // robots and the decision steps: on their way (driving; turning in place,
  // wheeled robots only), blocked (stalled short of the waypoint: no
  // progress, or slower than 1 cm/s) or arrived (waiting for the others).
  // With asynchronous decisions a robot never waits for the others: its
  // time is driving, turning, blocked, or staying (a stay the policy chose,
  // held until the next sensing tick); arrived is then only failed robots'.
  struct TimeUse {
    double driving = 0.0, turning = 0.0, blocked = 0.0, arrived = 0.0;
    double staying = 0.0, yielding = 0.0;
  };
  const TimeUse& time_use() const { return time_use_; }

  // Seconds of wall time spent inside mj_step, its call count, and the
  // contacts MuJoCo held after those calls, summed.
  double physics_seconds() const { return physics_seconds_; }
  long mj_steps() const { return mj_steps_; }
  long contacts_summed() const { return contacts_summed_; }
  // MuJoCo's warnings (mjtWarning) raised so far, by type, the overflows
  // that StepPhysics() handled by growing not counted.
  const std::array<long, mjNWARNING>& warnings() const { return warnings_; }
  PhysicsMemoryStats memory() const;

 private:
  void Grow();
  // How far robot i still has to go, and whether it moves no faster than
  // `speed` (RobotDriver: a point's distance and speed; a wheeled robot's
  // wheel travel and rim speed, turning included).
  double ToGo(int i) const;
  bool Slow(int i, double speed) const;

  std::shared_ptr<const PhysicsModel> model_;
  MjModelPtr own_model_;  // set once the contact budget has grown
  const mjModel* m_ = nullptr;
  MjDataPtr data_;
  const RobotDriver* driver_ = nullptr;  // the model's
  std::vector<Vec2> waypoints_;
  std::vector<mjtNum> saved_;     // time, qpos, qvel, qacc_warmstart, act
  std::vector<double> progress_;  // distance to the waypoint at a checkpoint
  std::vector<std::uint8_t> stuck_;
  // Per robot, the substeps its move's stall test waits beyond kSettleTime
  // for the robot to brake what it rolls with (RobotDriver::BrakeSeconds).
  std::vector<long> grace_;
  long GraceSteps(int i, double dt) const;
  std::vector<long> robot_stalls_, robot_timeouts_;
  std::vector<std::uint8_t> retired_;  // per robot: Retire
  std::vector<std::uint8_t> turning_;  // per robot, its controller's last call
  // Asynchronous moves: each robot's state, the substep its move started
  // (or its hold ends), and the simulation clock in substeps.
  enum class RobotState : std::uint8_t {
    kParked,
    kMoving,
    kHolding,
    kYielding
  };
  std::vector<RobotState> state_;
  std::vector<long> since_;
  long clock_ = 0;
  TimeUse time_use_;
  // RayClear's index: the geoms mj_ray would test (static primitives of the
  // obstacle group, not invisible), bucketed by their bounding circles.
  void IndexRayGeoms();
  std::vector<int> ray_geoms_;
  std::array<int, 4> border_geoms_{-1, -1, -1, -1};
  BoxBuckets ray_buckets_;
  bool ray_indexed_ = false;
  std::array<long, mjNWARNING> warnings_{};
  int grows_ = 0, max_contacts_ = 0, max_constraints_ = 0;
  long max_stack_ = 0;
  double physics_seconds_ = 0.0;
  long mj_steps_ = 0, contacts_summed_ = 0;
};

// One round of sensing (docs/design.md, Sensing): robot i (if active) measures
// target k when it is within range and, with line of sight on, a ray between
// them meets no obstacle. y = pos_k - p_i + v with v ~ N(0, (sigma0 + eta d)^2
// I) drawn at the true distance d; the recorded precision is computed from |y|,
// as the filter does not know d. The pairs in range come from a grid of the
// targets: O(N + M + pairs in range), not O(N M).
void Sense(const Simulation& sim, const SensorModel& sensor,
           const std::vector<Vec2>& robots, const std::vector<Vec2>& targets,
           const std::vector<std::uint8_t>& active, std::vector<Rng>* rngs,
           std::vector<std::vector<Measurement>>* out);
// The same with scratch memory kept from step to step (no allocation once
// warm).
struct SensingScratch {
  PointGrid targets;
  std::vector<int> near;
};
void Sense(const Simulation& sim, const SensorModel& sensor,
           const std::vector<Vec2>& robots, const std::vector<Vec2>& targets,
           const std::vector<std::uint8_t>& active, std::vector<Rng>* rngs,
           std::vector<std::vector<Measurement>>* out, SensingScratch* scratch);

}  // namespace aia

#endif  // AIA_SIM_SIMULATION_H_
