// The episode loop: one mission from start to success or max_steps. Each
// decision step reads like MuJoCo MPC's testspeed: the policy decides, the
// world rule checks the moves, targets move, physics runs, robots sense, the
// graph updates, beliefs predict and fuse, success is judged.
#ifndef AIA_RUNTIME_EPISODE_H_
#define AIA_RUNTIME_EPISODE_H_

#include <functional>
#include <memory>
#include <vector>

#include "aia/comm/graph.h"
#include "aia/core/rng.h"
#include "aia/estimation/belief.h"
#include "aia/estimation/sensor_model.h"
#include "aia/planning/policy.h"
#include "aia/scenario/config.h"
#include "aia/sim/simulation.h"
#include "aia/world/world.h"

namespace aia {

// Wall time per phase of the decision steps so far (seconds).
struct PhaseTimes {
  double physics = 0.0;  // inside mj_step
  double sensing = 0.0;  // rays and noise
  double fusion = 0.0;   // comm graph, predict, DKF, centralized filter, dets
  double policy = 0.0;   // Decide() and the world rule
  double total = 0.0;    // whole steps, the rest included
};

// The target models of the filter, from the world's targets.
BeliefLayout MakeBeliefLayout(const World& world);
SensorModel MakeSensorModel(const SensorConfig& config);

class Episode {
 public:
  // Called after each physics substep with the seconds since the step began
  // (for video frames).
  using SubstepHook = std::function<void(const Episode&, double elapsed)>;

  // Builds the world, the physics and the beliefs, and takes the first
  // measurements (step 0). Throws InputError for invalid scenarios.
  Episode(const Scenario& scenario, std::unique_ptr<Policy> policy);

  // One decision step. Does nothing once done().
  void Step(const SubstepHook& hook = {});
  bool done() const;

  int step() const { return step_; }
  bool success() const { return flowtime_ >= 0; }
  int flowtime() const { return flowtime_; }  // -1 until success
  bool all_localized() const { return all_localized_; }
  int localized_steps() const { return localized_steps_; }
  long invalid_moves() const { return invalid_moves_; }
  int NumLocalized() const;

  const Scenario& scenario() const { return scenario_; }
  const World& world() const { return world_; }
  const Simulation& sim() const { return *sim_; }
  const Policy& policy() const { return *policy_; }
  const CommNetwork& comm() const { return comm_; }
  const BeliefSet& beliefs() const { return fused_; }
  const BeliefSet& central() const { return central_; }
  const SensorModel& sensor() const { return sensor_; }
  const std::vector<Vec2>& robot_positions() const { return robot_pos_; }
  const std::vector<int>& robot_lattice() const { return robot_idx_; }
  const std::vector<Vec2>& target_positions() const { return target_pos_; }
  const std::vector<std::vector<Measurement>>& measurements() const {
    return z_;
  }
  // det Sigma_i^k of robot i's fused belief, row-major N x M.
  double Det(int robot, int target) const {
    return det_[robot * num_targets_ + target];
  }
  // min over active robots of det Sigma_i^k.
  double MinDet(int target) const { return min_det_[target]; }
  const PhaseTimes& times() const { return times_; }
  // What a policy sees at the current step.
  DecisionContext Context() const;
  Policy& mutable_policy() { return *policy_; }

 private:
  void Observe();  // sense, exchange, fuse, judge (the second half of a step)
  void MoveTargets();

  Scenario scenario_;
  World world_;
  std::unique_ptr<Simulation> sim_;
  std::unique_ptr<Policy> policy_;
  SensorModel sensor_;
  BeliefLayout layout_;
  BeliefSet predicted_, fused_, central_;
  CommNetwork comm_;
  Eigen::MatrixXd weights_;
  std::vector<Rng> sensor_rngs_, rule_rngs_;
  Rng target_rng_;
  std::vector<Vec2> robot_pos_, target_pos_, target_prev_;
  std::vector<Eigen::VectorXd> target_state_;
  std::vector<int> robot_idx_;
  std::vector<Move> moves_;
  std::vector<std::vector<Measurement>> z_;
  std::vector<double> det_, min_det_;
  int num_targets_ = 0;
  int step_ = 0;
  int flowtime_ = -1;
  bool all_localized_ = false;
  int localized_steps_ = 0;
  long invalid_moves_ = 0;
  PhaseTimes times_;
};

}  // namespace aia

#endif  // AIA_RUNTIME_EPISODE_H_
