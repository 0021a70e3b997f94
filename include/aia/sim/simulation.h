// The physics of a mission (docs/design.md, Physics): a MuJoCo model generated
// from the world, robots that track lattice waypoints with position actuators
// and real contacts, targets as mocap bodies, and ray sensing against
// obstacles. No process-wide MuJoCo callbacks: the caller sets waypoints and
// this class calls mj_step explicitly.
#ifndef AIA_SIM_SIMULATION_H_
#define AIA_SIM_SIMULATION_H_

#include <mujoco/mujoco.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "aia/core/rng.h"
#include "aia/core/types.h"
#include "aia/estimation/sensor_model.h"
#include "aia/scenario/config.h"
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

// Compiles MJCF text (through MuJoCo's virtual file system); throws
// std::runtime_error with MuJoCo's message if it does not compile.
MjModelPtr CompileMjcf(const std::string& xml);

struct PhysicsStepStats {
  int substeps = 0;  // mj_step calls
  bool all_arrived = false;
  bool timed_out = false;  // the step timeout passed first
};

// The compiled MuJoCo model of a world: generated once per instance and
// shared, read-only, by every simulation of it (mj_step takes the model as
// const), so that the runs of several policies on one world compile it once.
class PhysicsModel {
 public:
  // Generates the world's MJCF and compiles it; throws std::runtime_error
  // with MuJoCo's message if it does not compile.
  PhysicsModel(const World& world, const Scenario& scenario);

  const mjModel* model() const { return model_.get(); }
  const std::string& mjcf() const { return mjcf_; }
  const PhysicsConfig& physics() const { return physics_; }
  int num_robots() const { return static_cast<int>(starts_.size()); }
  int num_targets() const { return static_cast<int>(mocap_id_.size()); }

 private:
  friend class Simulation;
  std::string mjcf_;
  MjModelPtr model_;
  PhysicsConfig physics_;
  std::vector<Vec2> starts_;
  std::vector<int> qpos_adr_;  // per robot: qpos index of its x joint (y next)
  std::vector<int> qvel_adr_;
  std::vector<int> ctrl_adr_;
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
  const mjModel* model() const { return model_->model(); }
  mjData* data() { return data_.get(); }
  const mjData* data() const { return data_.get(); }
  const std::string& mjcf() const { return model_->mjcf(); }

  Vec2 RobotPosition(int i) const;
  Vec2 RobotVelocity(int i) const;
  void SetWaypoint(int i, const Vec2& p);
  Vec2 TargetPosition(int k) const;
  void SetTargetPosition(int k, const Vec2& p);

  // Runs mj_step until every robot is within the tolerance of its waypoint and
  // nearly still, or every robot that has not arrived has stalled (blocked by
  // a contact), or the step timeout passes. `on_substep(elapsed_seconds)` runs
  // after each mj_step (targets' mocap interpolation, video frames).
  PhysicsStepStats AdvanceToWaypoints(
      const std::function<void(double)>& on_substep = {});

  // Whether the segment between two points at sensor height meets no obstacle
  // (mj_ray against the obstacle geom group only).
  bool RayClear(const Vec2& from, const Vec2& to) const;

  // Seconds of wall time spent inside mj_step, and its call count.
  double physics_seconds() const { return physics_seconds_; }
  long mj_steps() const { return mj_steps_; }

 private:
  std::shared_ptr<const PhysicsModel> model_;
  MjDataPtr data_;
  std::vector<Vec2> waypoints_;
  double physics_seconds_ = 0.0;
  long mj_steps_ = 0;
};

// One round of sensing (docs/design.md, Sensing): robot i (if active) measures
// target k when it is within range and, with line of sight on, a ray between
// them meets no obstacle. y = pos_k - p_i + v with v ~ N(0, (sigma0 + eta d)^2
// I) drawn at the true distance d; the recorded precision is computed from |y|,
// as the filter does not know d.
void Sense(const Simulation& sim, const SensorModel& sensor,
           const std::vector<Vec2>& robots, const std::vector<Vec2>& targets,
           const std::vector<std::uint8_t>& active, std::vector<Rng>* rngs,
           std::vector<std::vector<Measurement>>* out);

}  // namespace aia

#endif  // AIA_SIM_SIMULATION_H_
