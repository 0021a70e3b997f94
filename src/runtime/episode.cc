#include "aia/runtime/episode.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "aia/core/check.h"
#include "aia/core/clock.h"
#include "aia/core/interrupt.h"
#include "aia/estimation/filter.h"
#include "aia/learning/network.h"

namespace aia {
namespace {

using Clock = std::chrono::steady_clock;

// Targets move during the first part of a step's physics, so video is smooth.
constexpr double kTargetMotionSeconds = 0.25;

// Every robot starts at the prior the scenario tells it.
TeamEstimate PriorEstimate(const World& world) {
  std::vector<TargetModel> models;
  std::vector<Eigen::VectorXd> means;
  std::vector<Eigen::MatrixXd> covs;
  for (const TargetPrior& p : world.priors) {
    models.push_back(p.model);
    means.push_back(p.mean);
    covs.push_back(p.cov);
  }
  return TeamEstimate(std::move(models), world.NumRobots(), means, covs);
}

}  // namespace

Episode::Episode(std::shared_ptr<const Instance> instance,
                 std::unique_ptr<Policy> policy)
    : Episode(instance, std::move(policy), instance->scenario.mission) {
  AIA_CHECK(policy_ != nullptr);
}

Episode::Episode(std::shared_ptr<const Instance> instance)
    : Episode(instance, nullptr, instance->scenario.mission) {}

Episode::Episode(std::shared_ptr<const Instance> instance,
                 std::unique_ptr<Policy> policy, const MissionConfig& mission)
    : instance_(std::move(instance)),
      mission_(mission),
      sim_(instance_->physics),
      policy_(std::move(policy)),
      estimate_(PriorEstimate(instance_->world)),
      target_rng_(instance_->scenario.seed, "targets.motion") {
  const Scenario& scenario = instance_->scenario;
  const World& world = instance_->world;
  const int n = world.NumRobots();
  num_targets_ = world.NumTargets();

  for (int k = 0; k < num_targets_; ++k) {
    target_state_.push_back(world.truth.targets[k]);
    target_pos_.push_back(world.TargetStart(k));
  }
  target_prev_ = target_pos_;

  comm_ = CommNetwork(scenario.communication, n, world.truth.failures,
                      scenario.seed);

  for (int i = 0; i < n; ++i) {
    sensor_rngs_.emplace_back(scenario.seed, "sensor", i);
    rule_rngs_.emplace_back(scenario.seed, "world_rule", i);
    robot_pos_.push_back(sim_.RobotPosition(i));
    robot_heading_.push_back(sim_.RobotHeading(i));
    robot_idx_.push_back(world.robot_starts[i]);
  }
  moves_.assign(n, Move::kStay);
  applied_.assign(n, Move::kStay);
  history_.Reset(n);
  made_.assign(n, Move::kStay);
  if (policy_) policy_->Reset(world.map, n, num_targets_, scenario.seed);
  ready_.assign(n, 1);
  stopped_robot_.assign(n, 0);
  from_ = robot_idx_;
  decisions_.assign(n, 0);
  drives_.assign(n, 0);
  if (async()) {
    const double rate =
        scenario.sensor.rate.value_or(DefaultSensorRate(scenario.robots.model));
    tick_period_ = SensingTickSteps(rate, sim_.model()->opt.timestep);
    next_tick_ = tick_period_;
    reserve_ =
        mission_.avoidance.value_or(kDefaultAvoidance) == Avoidance::kReserve;
  }
  if (reserve_) {
    const double release = 2.0 * scenario.robots.radius;
    release2_ = release * release;
    held_.assign(world.map.lattice().size(), 0);
    held_from_ = robot_idx_;
    for (int p : robot_idx_) ++held_[p];
    held_to_.assign(n, -1);
    pending_.assign(n, -1);
  }
  Observe();  // step 0: measurements at the starts, fused with the prior
  times_ = PhaseTimes{};  // phase times are those of the decision steps
}

void Episode::AddObserver(StepObserver* observer) {
  AIA_CHECK(observer != nullptr);
  observers_.push_back(observer);
}

void Episode::Run() {
  AIA_CHECK_MSG(policy_ != nullptr, "an episode without a policy cannot run");
  for (StepObserver* o : observers_) o->OnStart(*this);
  // Ctrl-C (when the command installed the handler) ends the mission after
  // the step in progress; what was done is written as usual.
  while (!done()) {
    if (Interrupted()) {
      interrupted_ = true;
      break;
    }
    Step();
  }
  for (StepObserver* o : observers_) o->OnEnd(*this);
}

bool Episode::done() const {
  if (stopped_) return true;
  if (step_ >= mission_.max_steps) return true;
  if (success() && mission_.stop_at_success) return true;
  return comm_.NumActive() == 0;
}

int Episode::NumLocalized() const {
  return estimate_.NumLocalized(mission_.eps);
}

void Episode::MoveTargets() {
  const World& world = instance_->world;
  for (int k = 0; k < num_targets_; ++k) {
    const TargetModel& model = estimate_.layout().model(k);
    target_prev_[k] = target_pos_[k];
    if (estimate_.layout().is_static(k)) continue;
    Eigen::VectorXd& x = target_state_[k];
    auto& next = next_state_;
    next.noalias() = model.A * x;
    next += model.b;
    const double sd = std::sqrt(model.q);
    for (int c = 0; c < next.size(); ++c) next[c] += sd * target_rng_.Normal();
    // The truth stays in the workspace (the filter's model does not know this).
    next[0] = std::clamp(next[0], 0.0, world.map.size().x());
    next[1] = std::clamp(next[1], 0.0, world.map.size().y());
    x = next;
    target_pos_[k] = x.head<2>();
  }
}

DecisionContext Episode::Context() const {
  DecisionContext ctx;
  ctx.step = step_;
  ctx.round = rounds_;
  ctx.map = &instance_->world.map;
  ctx.sensor = &instance_->scenario.sensor;
  ctx.eps = mission_.eps;
  ctx.robot_lattice = &robot_idx_;
  ctx.robot_positions = &robot_pos_;
  ctx.robot_headings = &robot_heading_;
  ctx.comm = &comm_;
  ctx.beliefs = &estimate_.fused();
  ctx.central = &estimate_.central();
  ctx.log_det_prior = &estimate_.log_det_prior();
  ctx.history = &history_;
  ctx.measurements = &z_;
  if (async()) ctx.ready = &ready_;
  ctx.knowledge = knowledge_;
  return ctx;
}

// The policy's moves into moves_: the team's context, without the
// centralized belief unless the policy is centralized.
PolicyStatus Episode::Decide(const DecisionContext& ctx) {
  DecisionContext given = ctx;
  if (!policy_->centralized()) given.central = nullptr;
  const PolicyStatus status = policy_->Decide(given, &moves_);
  ++rounds_;
  ++stats_.statuses[static_cast<int>(status)];
  return status;
}

void Episode::Step() {
  AIA_CHECK_MSG(policy_ != nullptr, "an episode without a policy cannot step");
  if (done()) return;
  if (async()) {
    StepAsync();
    return;
  }
  const auto t_step = Clock::now();
  const int n = instance_->world.NumRobots();
  const Lattice& lattice = instance_->world.map.lattice();

  // The policy decides on what the robots know now; the world rule applies.
  auto t0 = Clock::now();
  const DecisionContext ctx = Context();
  const PolicyStatus status = Decide(ctx);
  for (int i = 0; i < n; ++i) {
    if (!comm_.Active(i)) {
      applied_[i] = Move::kStay;
      sim_.SetWaypoint(i, robot_pos_[i]);  // a failed robot stops where it is
      sim_.Retire(i);
      continue;
    }
    const Move m = ApplyRule(i, lattice);
    drives_[i] += m == Move::kStay ? 0 : 1;
    sim_.SetWaypoint(i, lattice.Point(lattice.Next(robot_idx_[i], m)));
  }
  times_.policy += SecondsSince(t0);
  const Decision decision{moves_, applied_, status};
  for (StepObserver* o : observers_)
    stopped_ |= o->OnDecision(*this, ctx, decision) == ObserverStatus::kStop;
  if (stopped_) return;

  // Targets move and robots drive to their waypoints.
  MoveTargets();
  const double physics_before = sim_.physics_seconds();
  const PhysicsStepStats physics = sim_.AdvanceToWaypoints([&](double elapsed) {
    const double f = std::min(1.0, elapsed / kTargetMotionSeconds);
    for (int k = 0; k < num_targets_; ++k)
      sim_.SetTargetPosition(
          k, target_prev_[k] + f * (target_pos_[k] - target_prev_[k]));
    for (StepObserver* o : observers_) o->OnSubstep(*this, elapsed);
  });
  stats_.substeps += physics.substeps;
  stats_.sim_seconds += physics.substeps * sim_.model()->opt.timestep;
  if (physics.timed_out) ++stats_.physics_timeouts;
  if (!physics.all_arrived && !physics.timed_out) ++stats_.stalled_steps;
  for (int k = 0; k < num_targets_; ++k)
    sim_.SetTargetPosition(k, target_pos_[k]);
  times_.physics += sim_.physics_seconds() - physics_before;
  ++step_;
  for (int i = 0; i < n; ++i) {
    robot_pos_[i] = sim_.RobotPosition(i);
    robot_heading_[i] = sim_.RobotHeading(i);
    const int before = robot_idx_[i];
    const int idx = lattice.NearestFree(robot_pos_[i]);
    if (idx >= 0) robot_idx_[i] = idx;
    // The lattice move the robot made (none where it stayed, or stalled
    // short of the next point).
    made_[i] = MoveBetween(lattice, before, robot_idx_[i]);
    if (!comm_.Active(i)) continue;  // pushed, a failed robot makes no move
    history_.Record(i, made_[i]);
    ++decisions_[i];
  }
  Observe();
  times_.total += SecondsSince(t_step);
  for (StepObserver* o : observers_)
    stopped_ |= o->OnStep(*this) == ObserverStatus::kStop;
}

void Episode::StepAsync() {
  const auto t_step = Clock::now();
  const int n = instance_->world.NumRobots();
  const Lattice& lattice = instance_->world.map.lattice();

  // The robots whose moves have ended decide; the others drive on, their
  // destinations in the context as what they intend.
  auto t0 = Clock::now();
  const DecisionContext ctx = Context();
  const PolicyStatus status = Decide(ctx);
  for (int i = 0; i < n; ++i)
    if (ready_[i]) Apply(i, lattice);
  times_.policy += SecondsSince(t0);
  const Decision decision{moves_, applied_, status, &ready_};
  for (StepObserver* o : observers_)
    stopped_ |= o->OnDecision(*this, ctx, decision) == ObserverStatus::kStop;
  if (stopped_) return;
  std::fill(ready_.begin(), ready_.end(), 0);

  // Physics until some robot's move ends, sensing at every tick on the way.
  if (!targets_drawn_) {
    MoveTargets();
    targets_drawn_ = true;
  }
  const double dt = sim_.model()->opt.timestep;
  const double motion = std::min(kTargetMotionSeconds, tick_period_ * dt);
  const double round_start = sim_.clock_seconds();
  const double physics_before = sim_.physics_seconds();
  while (true) {
    const PhysicsStepStats physics =
        sim_.AdvanceMoves(next_tick_, &ended_, [&](double seconds) {
          const double f = std::min(1.0, (seconds - tick_start_ * dt) / motion);
          for (int k = 0; k < num_targets_; ++k)
            sim_.SetTargetPosition(
                k, target_prev_[k] + f * (target_pos_[k] - target_prev_[k]));
          if (reserve_) Reservations(lattice);
          for (StepObserver* o : observers_)
            o->OnSubstep(*this, seconds - round_start);
        });
    stats_.substeps += physics.substeps;
    stats_.sim_seconds = sim_.clock_seconds();
    if (physics.late > 0) ++stats_.physics_timeouts;
    if (physics.stalled > 0) ++stats_.stalled_steps;
    for (int i : ended_) EndMove(i, lattice);
    if (!ended_.empty()) {
      // The slowest active robot's decisions; a robot whose failure step
      // that reaches stops now, not at the next tick (then the slowest of
      // the others counts).
      const auto slowest = [&] {
        long fewest = -1;
        for (int i = 0; i < n; ++i)
          if (comm_.Active(i) && (fewest < 0 || decisions_[i] < fewest))
            fewest = decisions_[i];
        if (fewest >= 0) step_ = static_cast<int>(fewest);
      };
      slowest();
      while (comm_.ApplyFailures(step_)) {
        knowledge_ = NewKnowledgeStamp();  // the graph and the active robots
        StopFailedRobots();
        slowest();
      }
    }
    // The moves that complete max_steps are sensed and judged, as every
    // lockstep step is: a last tick now when the next one is later.
    // Likewise when the last robot has failed: the team's end is judged.
    if (sim_.clock() >= next_tick_ ||
        ((step_ >= mission_.max_steps || comm_.NumActive() == 0) &&
         tick_start_ < sim_.clock()))
      Tick();
    if (!ended_.empty() || stopped_ || done()) break;
  }
  times_.physics += sim_.physics_seconds() - physics_before;
  times_.total += SecondsSince(t_step);
}

// The world rule on robot i's move (an invalid one is replaced and
// counted): the move applied.
Move Episode::ApplyRule(int i, const Lattice& lattice) {
  bool replaced = false;
  applied_[i] = ApplyWorldRule(lattice, robot_idx_[i], moves_[i], rule_rngs_[i],
                               &replaced);
  invalid_moves_ += replaced ? 1 : 0;
  return applied_[i];
}

// Robot i's next move starts now: a stay holds it at its point until the
// next sensing tick; a failed robot stops where it is.
void Episode::Apply(int i, const Lattice& lattice) {
  if (!comm_.Active(i)) {  // failed before it could decide
    applied_[i] = Move::kStay;
    stopped_robot_[i] = 1;
    sim_.SetWaypoint(i, robot_pos_[i]);
    sim_.Park(i);
    return;
  }
  const Move m = ApplyRule(i, lattice);
  from_[i] = robot_idx_[i];
  if (m == Move::kStay) {
    sim_.SetWaypoint(i, lattice.Point(robot_idx_[i]));
    sim_.Hold(i, next_tick_);
    return;
  }
  const int to = lattice.Next(robot_idx_[i], m);
  if (reserve_ && held_[to] > 0) {  // taken: wait at its point for it
    pending_[i] = to;
    sim_.SetWaypoint(i, lattice.Point(robot_idx_[i]));
    sim_.Hold(i, next_tick_, /*yielding=*/true);
    robot_idx_[i] = to;  // what it intends, as a robot on its way
    return;
  }
  StartMove(i, to, lattice);
}

void Episode::StartMove(int i, int to, const Lattice& lattice) {
  robot_idx_[i] = to;
  ++drives_[i];
  if (reserve_) {
    ++held_[to];
    held_to_[i] = to;
    pending_[i] = -1;
  }
  sim_.StartMove(i, lattice.Point(to));
}

void Episode::Reservations(const Lattice& lattice) {
  const int n = static_cast<int>(held_to_.size());
  for (int i = 0; i < n; ++i) {
    const int from = held_from_[i];
    if (held_to_[i] >= 0 && from >= 0 &&
        (sim_.RobotPosition(i) - lattice.Point(from)).squaredNorm() >=
            release2_) {
      --held_[from];
      held_from_[i] = -1;
    }
  }
  for (int i = 0; i < n; ++i)
    if (pending_[i] >= 0 && held_[pending_[i]] == 0)
      StartMove(i, pending_[i], lattice);
}

// The lattice point robot i is at when its move ends or it fails: the free
// point nearest to it; with reservations, that point where no other robot
// holds it (a move cut short, say by the step timeout, can end anywhere,
// a wheeled robot's even beyond both of its points), else the nearer of
// its own points.
int Episode::PointAt(int i, const Lattice& lattice) const {
  const int free = lattice.NearestFree(robot_pos_[i]);
  if (!reserve_) return free;
  const int own[2] = {held_from_[i], held_to_[i]};
  const auto mine = [&](int p) {
    return p >= 0 && (p == own[0] || p == own[1]);
  };
  if (free >= 0 && (held_[free] == 0 || mine(free))) return free;
  int nearest = -1;
  double best = 0.0;
  for (const int p : own) {
    if (p < 0) continue;
    const double d = (robot_pos_[i] - lattice.Point(p)).squaredNorm();
    if (nearest < 0 || d < best) {
      nearest = p;
      best = d;
    }
  }
  return nearest >= 0 ? nearest : free;
}

// Robot i's move ended (arrived, stalled, timed out, or its stay is over):
// where it is, the lattice move it made, and it decides next.
void Episode::EndMove(int i, const Lattice& lattice) {
  robot_pos_[i] = sim_.RobotPosition(i);
  robot_heading_[i] = sim_.RobotHeading(i);
  const int idx = PointAt(i, lattice);
  robot_idx_[i] = idx >= 0 ? idx : from_[i];
  made_[i] = MoveBetween(lattice, from_[i], robot_idx_[i]);
  history_.Record(i, made_[i]);
  if (reserve_) HoldOnly(i, robot_idx_[i]);
  from_[i] = robot_idx_[i];
  ++decisions_[i];
  ready_[i] = comm_.Active(i) ? 1 : 0;
}

// A robot that failed stops where it is, mid-move or not, and lets go of
// the points it held (at the tick that applies its failure, or between
// ticks when the step reaches its failure step).
void Episode::StopFailedRobots() {
  const int n = instance_->world.NumRobots();
  for (int i = 0; i < n; ++i) {
    if (comm_.Active(i) || stopped_robot_[i]) continue;
    robot_pos_[i] = sim_.RobotPosition(i);
    stopped_robot_[i] = 1;
    ready_[i] = 0;
    sim_.SetWaypoint(i, robot_pos_[i]);
    sim_.Park(i);
    const Lattice& lattice = instance_->world.map.lattice();
    const int at = PointAt(i, lattice);
    if (at >= 0) robot_idx_[i] = at;
    if (reserve_) {
      HoldOnly(i, at);
      HoldAround(i, at, lattice);
    }
  }
}

// Robot i lets go of the points it held (and of one it waited for) and
// holds `at` (none where it is -1).
void Episode::HoldOnly(int i, int at) {
  if (held_from_[i] >= 0) --held_[held_from_[i]];
  if (held_to_[i] >= 0) --held_[held_to_[i]];
  held_to_[i] = pending_[i] = -1;
  held_from_[i] = at;
  if (at >= 0) ++held_[at];
}

// A failed robot stops between points, or off them: every other point a
// robot there would touch it from (within two radii, and a margin for a
// wheeled robot's braking) is held for good too.
void Episode::HoldAround(int i, int at, const Lattice& lattice) {
  constexpr double kBrakingMargin = 0.1;  // metres
  const double reach = std::sqrt(release2_) + kBrakingMargin;
  const Vec2 p = robot_pos_[i];
  const int span = static_cast<int>(std::ceil(reach / lattice.step()));
  ForEachInWindow(lattice, lattice.NearestPoint(p), span, [&](int q, int, int) {
    if (q != at && lattice.Free(q) && (lattice.Point(q) - p).norm() < reach)
      ++held_[q];
  });
}

// A sensing tick: every robot senses from where it is (mid-move too), the
// graph and the filter update, success is judged; targets take their next
// step of dynamics, reached by interpolation before the next tick.
void Episode::Tick() {
  const int n = instance_->world.NumRobots();
  for (int i = 0; i < n; ++i) {
    robot_pos_[i] = sim_.RobotPosition(i);
    robot_heading_[i] = sim_.RobotHeading(i);
  }
  for (int k = 0; k < num_targets_; ++k)
    sim_.SetTargetPosition(k, target_pos_[k]);
  ++tick_;
  Observe();
  StopFailedRobots();
  for (StepObserver* o : observers_)
    stopped_ |= o->OnStep(*this) == ObserverStatus::kStop;
  MoveTargets();
  tick_start_ = sim_.clock();
  next_tick_ += tick_period_;
}

void Episode::Observe() {
  auto t0 = Clock::now();
  knowledge_ = NewKnowledgeStamp();  // a new graph, measurements and beliefs
  comm_.Update(step_, robot_pos_);
  Sense(sim_, instance_->scenario.sensor, robot_pos_, target_pos_,
        comm_.active(), &sensor_rngs_, &z_, &sensing_);
  times_.sensing += SecondsSince(t0);

  t0 = Clock::now();
  // Predict (not at step 0: the prior is the belief at time 0), exchange over
  // this step's graph, fuse with the robot's own measurements.
  try {
    estimate_.Update(filter_step() > 0, comm_.AllNeighbors(),
                     instance_->scenario.communication.kappa_self, z_,
                     robot_pos_, comm_.active(), PolicyRunner(),
                     comm_.graph_stamp());
  } catch (const EstimateDiverged& e) {
    // Unstable dynamics that no robot measures: the model, not the robots,
    // makes the mission impossible; stop with the key to blame.
    const int k = e.target();
    throw instance_->scenario.ErrorAt(
        k >= 0 ? "targets.list[" + std::to_string(k) + "].dynamics" : "targets",
        "the estimate of target " + std::to_string(k) + " diverges at step " +
            std::to_string(filter_step()) + ": " + e.what() +
            " (the dynamics are unstable and no robot measures the target; "
            "a stable A, or robots that reach it sooner)");
  }

  // Judge the mission on the active robots' best estimates.
  all_localized_ = NumLocalized() == num_targets_;
  if (all_localized_) {
    ++localized_steps_;
    if (flowtime_ < 0) {
      // In async a tick during the first moves finds no decision completed
      // yet; F = 0 is kept for a mission localized at the start.
      flowtime_ = async() && tick_ > 0 ? std::max(step_, 1) : step_;
      stats_.success_seconds = stats_.sim_seconds;
    }
  }
  times_.fusion += SecondsSince(t0);
}

std::string EndOfMissionWarnings(const Episode& e, long moves,
                                 const std::string& what) {
  return UnstableStateWarning(e.sim().warnings(), e.sim().robot_model(), what) +
         NoArrivalWarning(e.drives(), e.sim().robot_timeouts(),
                          e.sim().robot_stalls(), moves, what);
}

}  // namespace aia
