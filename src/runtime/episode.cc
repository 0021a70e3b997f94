#include "aia/runtime/episode.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "aia/core/check.h"
#include "aia/estimation/filter.h"

namespace aia {
namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Targets move during the first part of a step's physics, so video is smooth.
constexpr double kTargetMotionSeconds = 0.25;

}  // namespace

BeliefLayout MakeBeliefLayout(const World& world) {
  std::vector<TargetModel> models;
  for (const TargetInstance& t : world.targets) {
    TargetModel m;
    m.dim = t.dynamics.dim();
    m.A = t.dynamics.A;
    m.b = t.dynamics.b;
    m.Q = t.dynamics.q * Eigen::MatrixXd::Identity(m.dim, m.dim);
    m.is_static = t.dynamics.IsStatic();
    models.push_back(std::move(m));
  }
  return BeliefLayout(std::move(models));
}

SensorModel MakeSensorModel(const SensorConfig& c) {
  SensorModel s;
  s.range = c.range;
  s.eta = c.eta;
  s.sigma0 = c.sigma0;
  s.line_of_sight = c.line_of_sight;
  return s;
}

Episode::Episode(const Scenario& scenario, std::unique_ptr<Policy> policy)
    : scenario_(scenario),
      world_(World::Build(scenario)),
      policy_(std::move(policy)),
      sensor_(MakeSensorModel(scenario.sensor)),
      layout_(MakeBeliefLayout(world_)),
      target_rng_(scenario.seed, "targets.motion") {
  AIA_CHECK(policy_ != nullptr);
  sim_ = std::make_unique<Simulation>(world_, scenario_);
  const int n = world_.NumRobots();
  num_targets_ = world_.NumTargets();

  std::vector<Eigen::VectorXd> means;
  std::vector<Eigen::MatrixXd> covs;
  for (const TargetInstance& t : world_.targets) {
    means.push_back(t.prior_mean);
    covs.push_back(t.prior_cov);
    target_state_.push_back(t.x0);
    target_pos_.push_back(t.Position());
  }
  target_prev_ = target_pos_;
  predicted_ = BeliefSet(&layout_, n);
  fused_ = BeliefSet(&layout_, n);
  central_ = BeliefSet(&layout_, 1);
  predicted_.SetPrior(means, covs);
  fused_.SetPrior(means, covs);
  central_.SetPrior(means, covs);

  CommParams cp;
  cp.range_limited = scenario_.communication.mode == CommMode::kRange;
  cp.range = scenario_.communication.range;
  cp.loss_lambda = scenario_.communication.packet_loss_lambda;
  std::vector<ScheduledFailure> failures;
  for (const RobotFailure& f : world_.failures)
    failures.push_back({f.robot, f.step});
  comm_ = CommNetwork(cp, n, failures, scenario_.seed);

  for (int i = 0; i < n; ++i) {
    sensor_rngs_.emplace_back(scenario_.seed, "sensor", i);
    rule_rngs_.emplace_back(scenario_.seed, "world_rule", i);
    robot_pos_.push_back(sim_->RobotPosition(i));
    robot_idx_.push_back(world_.robot_starts[i]);
  }
  moves_.assign(n, Move::kStay);
  det_.assign(static_cast<size_t>(n) * num_targets_, 1.0);
  min_det_.assign(num_targets_, 1.0);
  policy_->Reset(world_, scenario_.seed);
  Observe();  // step 0: measurements at the starts, fused with the prior
}

bool Episode::done() const {
  if (step_ >= scenario_.mission.max_steps) return true;
  if (success() && scenario_.mission.stop_at_success) return true;
  return comm_.NumActive() == 0;
}

int Episode::NumLocalized() const {
  int count = 0;
  for (int k = 0; k < num_targets_; ++k)
    count += min_det_[k] <= scenario_.mission.eps ? 1 : 0;
  return count;
}

void Episode::MoveTargets() {
  for (int k = 0; k < num_targets_; ++k) {
    const DynamicsConfig& dyn = world_.targets[k].dynamics;
    target_prev_[k] = target_pos_[k];
    if (dyn.IsStatic()) continue;
    Eigen::VectorXd& x = target_state_[k];
    Eigen::VectorXd next = dyn.A * x + dyn.b;
    const double sd = std::sqrt(dyn.q);
    for (int c = 0; c < next.size(); ++c) next[c] += sd * target_rng_.Normal();
    // The truth stays in the workspace (the filter's model does not know this).
    next[0] = std::clamp(next[0], 0.0, world_.size.x());
    next[1] = std::clamp(next[1], 0.0, world_.size.y());
    x = next;
    target_pos_[k] = x.head<2>();
  }
}

DecisionContext Episode::Context() const {
  DecisionContext ctx;
  ctx.step = step_;
  ctx.world = &world_;
  ctx.sensor = &sensor_;
  ctx.eps = scenario_.mission.eps;
  ctx.positions = &robot_idx_;
  ctx.comm = &comm_;
  ctx.beliefs = &fused_;
  ctx.central = &central_;
  return ctx;
}

void Episode::Step(const SubstepHook& hook) {
  if (done()) return;
  const auto t_step = Clock::now();
  const int n = world_.NumRobots();
  const Lattice& lattice = world_.lattice;

  // The policy decides on what the robots know now; the world rule applies.
  auto t0 = Clock::now();
  const DecisionContext ctx = Context();
  policy_->Decide(ctx, &moves_);
  for (int i = 0; i < n; ++i) {
    if (!comm_.Active(i)) {
      sim_->SetWaypoint(i, robot_pos_[i]);  // a failed robot stops where it is
      continue;
    }
    bool replaced = false;
    const Move m = ApplyWorldRule(lattice, robot_idx_[i], moves_[i],
                                  rule_rngs_[i], &replaced);
    invalid_moves_ += replaced ? 1 : 0;
    sim_->SetWaypoint(i, lattice.Point(lattice.Next(robot_idx_[i], m)));
  }
  times_.policy += Since(t0);

  // Targets move and robots drive to their waypoints.
  MoveTargets();
  const double physics_before = sim_->physics_seconds();
  Simulation& sim = *sim_;
  sim.AdvanceToWaypoints([&](double elapsed) {
    const double f = std::min(1.0, elapsed / kTargetMotionSeconds);
    for (int k = 0; k < num_targets_; ++k)
      sim.SetTargetPosition(
          k, target_prev_[k] + f * (target_pos_[k] - target_prev_[k]));
    if (hook) hook(*this, elapsed);
  });
  for (int k = 0; k < num_targets_; ++k)
    sim.SetTargetPosition(k, target_pos_[k]);
  times_.physics += sim.physics_seconds() - physics_before;
  ++step_;
  for (int i = 0; i < n; ++i) {
    robot_pos_[i] = sim.RobotPosition(i);
    const int idx = lattice.NearestFree(robot_pos_[i]);
    if (idx >= 0) robot_idx_[i] = idx;
  }
  Observe();
  times_.total += Since(t_step);
}

void Episode::Observe() {
  const int n = world_.NumRobots();
  auto t0 = Clock::now();
  comm_.Update(step_, robot_pos_);
  Sense(*sim_, sensor_, robot_pos_, target_pos_, comm_.active(), &sensor_rngs_,
        &z_);
  times_.sensing += Since(t0);

  t0 = Clock::now();
  // Predict (not at step 0: the prior is the belief at time 0), exchange over
  // this step's graph, fuse with the robot's own measurements.
  predicted_.data() = fused_.data();
  if (step_ > 0) {
    Predict(&predicted_);
    Predict(&central_);
  }
  FusionWeights(comm_.AllNeighbors(), scenario_.communication.kappa_self,
                &weights_);
  Fuse(predicted_, weights_, z_, robot_pos_, &fused_);
  CentralUpdate(z_, robot_pos_, &central_);

  // Judge the mission on the active robots.
  bool all = true;
  for (int k = 0; k < num_targets_; ++k) {
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i < n; ++i) {
      const double d = fused_.DetCovariance(i, k);
      det_[static_cast<size_t>(i) * num_targets_ + k] = d;
      if (comm_.Active(i)) best = std::min(best, d);
    }
    min_det_[k] = best;
    if (!(best <= scenario_.mission.eps)) all = false;
  }
  all_localized_ = all;
  if (all) {
    ++localized_steps_;
    if (flowtime_ < 0) flowtime_ = step_;
  }
  times_.fusion += Since(t0);
}

}  // namespace aia
