// The episode loop: one mission from start to success or max_steps. Each
// decision step reads like MuJoCo MPC's testspeed: the policy decides, the
// world rule checks the moves, targets move, physics runs, robots sense, the
// graph updates, beliefs predict and fuse, success is judged. What else a
// command needs (result files, metrics, video, datasets) watches the loop as
// a StepObserver, after Drake's simulator monitors: `aia run` and
// `aia render` share this one loop.
#ifndef AIA_RUNTIME_EPISODE_H_
#define AIA_RUNTIME_EPISODE_H_

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "aia/comm/graph.h"
#include "aia/core/rng.h"
#include "aia/estimation/belief.h"
#include "aia/estimation/filter.h"
#include "aia/estimation/sensor_model.h"
#include "aia/estimation/team_estimate.h"
#include "aia/planning/policy.h"
#include "aia/runtime/instance.h"
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

// What happened besides the outcome: kept, not dropped.
struct EpisodeStats {
  // Decisions per PolicyStatus (indexed by its value).
  std::array<long, kNumPolicyStatuses> statuses{};
  // Steps whose physics hit physics.step_timeout, and steps that ended with
  // a robot blocked short of its waypoint (a contact) before the timeout.
  // With mission.decisions async both count rounds (the physics between
  // two batches of decisions), of which a step has one or more, and one
  // round can count in both.
  long physics_timeouts = 0;
  long stalled_steps = 0;
  long substeps = 0;         // mj_step calls
  double sim_seconds = 0.0;  // simulated time
  // Simulated seconds when the mission succeeded (-1 until then).
  double success_seconds = -1.0;
};

class Episode;

// One decision: what the policy wanted, what the world applied (an invalid
// move replaced by the world rule; kStay for failed robots), and its status.
struct Decision {
  const std::vector<Move>& wanted;
  const std::vector<Move>& applied;
  PolicyStatus status;
  // mission.decisions async: the robots that decided (the others' entries
  // are their moves in progress); null: all of them (lockstep).
  const std::vector<std::uint8_t>* ready = nullptr;
};

// What an observer tells the loop after a decision or a step (Drake's
// monitors return a status the same way).
enum class ObserverStatus {
  kContinue,
  // End the episode: after a decision, before anything moves (the step is
  // not counted; every observer still sees the decision); after a step,
  // there. Run() still calls every OnEnd, and Episode::stopped() says so.
  kStop,
};

// Watches an episode. Called on the loop's thread, in the order added; the
// episode's state is read-only to it.
class StepObserver {
 public:
  virtual ~StepObserver() = default;
  // Once, from Run(), before the first step: the state at step 0 (the prior
  // fused with the measurements at the starts).
  virtual void OnStart(const Episode& /*episode*/) {}
  // After every decision, before anything moves. `context` is the whole
  // team's (the centralized belief included, whatever the acting policy
  // was given), so that an observer can ask another policy what it would
  // have done (dataset labels).
  virtual ObserverStatus OnDecision(const Episode& /*episode*/,
                                    const DecisionContext& /*context*/,
                                    const Decision& /*decision*/) {
    return ObserverStatus::kContinue;
  }
  // After each physics substep; `elapsed`: simulated seconds into the step
  // (async: since the decision).
  virtual void OnSubstep(const Episode& /*episode*/, double /*elapsed*/) {}
  // After each step's sensing, fusion and judging (async: after each
  // sensing tick, Episode::filter_step).
  virtual ObserverStatus OnStep(const Episode& /*episode*/) {
    return ObserverStatus::kContinue;
  }
  // Once, from Run(), when the episode is done.
  virtual void OnEnd(const Episode& /*episode*/) {}
};

class Episode {
 public:
  // Sets up the physics and the beliefs on a shared instance, with the
  // instance's mission settings or `mission`, and takes the first
  // measurements (step 0).
  Episode(std::shared_ptr<const Instance> instance,
          std::unique_ptr<Policy> policy);
  Episode(std::shared_ptr<const Instance> instance,
          std::unique_ptr<Policy> policy, const MissionConfig& mission);
  // The state at step 0 only, with no policy (planning from the start, as
  // `aia plan` and eval's F* do): Context() and the accessors work, Run()
  // and Step() refuse, policy() must not be called.
  explicit Episode(std::shared_ptr<const Instance> instance);
  // Beliefs point into the episode (their layout): it stays where it is.
  Episode(const Episode&) = delete;
  Episode& operator=(const Episode&) = delete;

  // Observers are not owned and must outlive the episode's use of them.
  void AddObserver(StepObserver* observer);

  // OnStart, steps until done(), OnEnd.
  void Run();
  // One decision step. Does nothing once done().
  void Step();
  // The mission is over (max_steps, success, no robot left) or an observer
  // stopped it.
  bool done() const;
  bool stopped() const { return stopped_; }  // by an observer
  // Run() ended early on Ctrl-C (core/interrupt.h), steps left undone.
  bool interrupted() const { return interrupted_; }

  // Decision steps: in lockstep the team's; in async the fewest decisions
  // any active robot has completed (the slowest robot's).
  int step() const { return step_; }
  bool async() const { return mission_.decisions == Decisions::kAsync; }
  // The filter's steps (sensing, exchange, fusion), which the trace counts:
  // step() in lockstep, sensing ticks in async.
  int filter_step() const { return async() ? tick_ : step_; }
  // The simulated clock, seconds.
  double clock_seconds() const { return sim_.clock_seconds(); }
  // Moves (a stay included) each robot has completed.
  const std::vector<long>& decisions() const { return decisions_; }
  // Moves each robot was sent on to another lattice point (stays and waits
  // for a held point excluded), arrived or not.
  const std::vector<long>& drives() const { return drives_; }
  bool success() const { return flowtime_ >= 0; }
  int flowtime() const { return flowtime_; }  // -1 until success
  // Simulated seconds of the mission: until success, else so far.
  double mission_seconds() const {
    return success() ? stats_.success_seconds : stats_.sim_seconds;
  }
  bool all_localized() const { return all_localized_; }
  int localized_steps() const { return localized_steps_; }
  long invalid_moves() const { return invalid_moves_; }
  int NumLocalized() const;

  const Instance& instance() const { return *instance_; }
  const Scenario& scenario() const { return instance_->scenario; }
  const MissionConfig& mission() const { return mission_; }
  const World& world() const { return instance_->world; }
  const Simulation& sim() const { return sim_; }
  const Policy& policy() const { return *policy_; }
  const CommNetwork& comm() const { return comm_; }
  // What the team knows (the fused beliefs, the centralized one, the best
  // estimates); the accessors below read it.
  const TeamEstimate& estimate() const { return estimate_; }
  const BeliefSet& beliefs() const { return estimate_.fused(); }
  const BeliefSet& central() const { return estimate_.central(); }
  const SensorModel& sensor() const { return scenario().sensor; }
  const std::vector<Vec2>& robot_positions() const { return robot_pos_; }
  // Radians from +x (0 for point robots).
  const std::vector<double>& robot_headings() const { return robot_heading_; }
  const std::vector<int>& robot_lattice() const { return robot_idx_; }
  // The lattice move each robot made in the last step (kStay: it stayed, or
  // stalled short of its next point), and every robot's last move and
  // reversals in a row so far: what DecisionContext::history gives the
  // policy.
  const std::vector<Move>& moves_made() const { return made_; }
  const MoveHistory& history() const { return history_; }
  // Ground truth, for scoring and video: the targets' positions and states.
  const std::vector<Vec2>& target_positions() const { return target_pos_; }
  const std::vector<Eigen::VectorXd>& target_states() const {
    return target_state_;
  }
  const std::vector<std::vector<Measurement>>& measurements() const {
    return z_;
  }
  // det Sigma_i^k of robot i's fused belief, row-major N x M.
  double Det(int robot, int target) const {
    return estimate_.Det(robot, target);
  }
  // The team's best estimate of target k (estimation/belief.h): the active
  // robot whose belief has the smallest det Sigma_k, or -1 if none is active.
  int BestRobot(int target) const { return estimate_.BestRobot(target); }
  // min over active robots of det Sigma_i^k.
  double MinDet(int target) const { return estimate_.MinDet(target); }
  // log det Sigma_0^k per target (what the robots were told).
  const std::vector<double>& log_det_prior() const {
    return estimate_.log_det_prior();
  }
  const PhaseTimes& times() const { return times_; }
  const EpisodeStats& stats() const { return stats_; }
  // The whole team's view of the current step (the centralized belief
  // included); the policy is given the same without it unless centralized.
  DecisionContext Context() const;

 private:
  void Observe();  // sense, exchange, fuse, judge (the second half of a step)
  void MoveTargets();
  PolicyStatus Decide(const DecisionContext& ctx);
  // mission.decisions async: one round (the ready robots decide, physics
  // runs until a robot's move ends, sensing ticks on the way), and one tick.
  void StepAsync();
  void Tick();
  // Failed robots still driving stop where they are and let go of their
  // points (async).
  void StopFailedRobots();
  void Apply(int i, const Lattice& lattice);
  void StartMove(int i, int to, const Lattice& lattice);
  void EndMove(int i, const Lattice& lattice);
  // The lattice point robot i stands at when its move ends or it fails:
  // the nearest free one; with reservations, that one unless another robot
  // holds it, else the nearer of the points robot i holds.
  int PointAt(int i, const Lattice& lattice) const;
  // The world rule on robot i's policy move: applied_[i], counted if
  // replaced.
  Move ApplyRule(int i, const Lattice& lattice);
  // Robot i holds `at` alone (-1: nothing): what it held and waited for
  // let go.
  void HoldOnly(int i, int at);
  // Failed robot i, at point `at`: holds for good the other points within
  // two radii (and a braking margin) of where it stopped.
  void HoldAround(int i, int at, const Lattice& lattice);
  // mission.avoidance reserve, after each substep: points let go, waiting
  // robots started.
  void Reservations(const Lattice& lattice);

  std::shared_ptr<const Instance> instance_;
  MissionConfig mission_;
  Simulation sim_;
  std::unique_ptr<Policy> policy_;
  TeamEstimate estimate_;
  CommNetwork comm_;
  SensingScratch sensing_;
  std::vector<Rng> sensor_rngs_, rule_rngs_;
  Rng target_rng_;
  std::vector<Vec2> robot_pos_, target_pos_, target_prev_;
  std::vector<double> robot_heading_;
  std::vector<Eigen::VectorXd> target_state_;
  // MoveTargets' scratch: a target's state has 2 or 4 entries, and teams
  // mix the two, so the room for 4 is kept inline (no allocation a step).
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 4, 1> next_state_;
  std::vector<int> robot_idx_;
  std::vector<Move> moves_, applied_;
  // The lattice moves the robots made in the last step, and all of them so
  // far (the policies' contexts, the move observer).
  std::vector<Move> made_;
  MoveHistory history_;
  std::vector<std::vector<Measurement>> z_;
  std::vector<StepObserver*> observers_;
  int num_targets_ = 0;
  int step_ = 0;
  int rounds_ = 0;  // the policy's decisions so far (DecisionContext::round)
  // DecisionContext::knowledge: new at every Observe and failure.
  std::uint64_t knowledge_ = 0;
  int flowtime_ = -1;
  bool stopped_ = false;
  bool interrupted_ = false;
  bool all_localized_ = false;
  int localized_steps_ = 0;
  long invalid_moves_ = 0;
  // Async: who decides next, where each move started, moves completed, the
  // moves that just ended, and the sensing clock (substeps).
  std::vector<std::uint8_t> ready_;
  std::vector<std::uint8_t> stopped_robot_;  // failed, stopped for good
  std::vector<int> from_;
  std::vector<long> decisions_, drives_;
  std::vector<int> ended_;
  int tick_ = 0;
  long tick_period_ = 1, next_tick_ = 0, tick_start_ = 0;
  bool targets_drawn_ = false;
  // mission.avoidance reserve: robots holding each lattice point; per robot
  // the point it left (until it is 2 radii away), the point it drives to,
  // and the point it waits for (-1: none).
  bool reserve_ = false;
  double release2_ = 0.0;
  std::vector<int> held_;
  std::vector<int> held_from_, held_to_, pending_;
  PhaseTimes times_;
  EpisodeStats stats_;
};

// The lines a command prints on stderr after a mission (`what` names it):
// UnstableStateWarning and NoArrivalWarning of its physics, `moves` the
// lattice moves completed (a MoveObserver's count); "" when all went well.
std::string EndOfMissionWarnings(const Episode& e, long moves,
                                 const std::string& what);

}  // namespace aia

#endif  // AIA_RUNTIME_EPISODE_H_
