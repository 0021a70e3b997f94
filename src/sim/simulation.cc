#include "aia/sim/simulation.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <numeric>
#include <stdexcept>

#include "aia/core/check.h"
#include "aia/core/clock.h"
#include "aia/world/mjcf.h"

namespace aia {
namespace {

thread_local std::string last_warning;

// Called by MuJoCo in place of its own handler, which would print, write
// MUJOCO_LOG.TXT, wait for Enter and exit. MuJoCo does not expect it to
// return: the exception unwinds through its C frames (libmujoco is built with
// unwind tables, as every x86-64 object is by default).
void OnMujocoError(const char* message) {
  throw PhysicsError(std::string("MuJoCo: ") + message);
}

void OnMujocoWarning(const char* message) { last_warning = message; }

template <typename T>
void CopyArray(const T* from, int count, T* to) {
  if (count > 0) std::memcpy(to, from, sizeof(T) * count);
}

}  // namespace

void InstallMujocoHandlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    mju_user_error = OnMujocoError;
    mju_user_warning = OnMujocoWarning;
  });
}

const std::string& LastMujocoWarning() { return last_warning; }

const char* MujocoWarningName(int warning) {
  static const char* const kNames[mjNWARNING] = {
      "inertia",  "contact_full", "constraint_full", "visual_geom_full",
      "bad_qpos", "bad_qvel",     "bad_qacc",        "bad_ctrl"};
  return warning >= 0 && warning < mjNWARNING ? kNames[warning] : "unknown";
}

std::string UnstableStateReport(const std::array<long, mjNWARNING>& warnings) {
  long total = 0;
  std::string types;
  for (const int w :
       {mjWARN_BADQPOS, mjWARN_BADQVEL, mjWARN_BADQACC, mjWARN_BADCTRL}) {
    if (warnings[w] == 0) continue;
    total += warnings[w];
    types += std::string(types.empty() ? "" : ", ") + MujocoWarningName(w) +
             " " + std::to_string(warnings[w]);
  }
  if (total == 0) return "";
  return "MuJoCo reset an unstable state " + std::to_string(total) +
         (total == 1 ? " time (" : " times (") + types + ")";
}

std::string UnstableStateWarning(const std::array<long, mjNWARNING>& warnings,
                                 RobotModel model, const std::string& what) {
  const std::string report = UnstableStateReport(warnings);
  if (report.empty()) return "";
  return "warning: " + what + ": " + report +
         ": the robots' motion after it is not physical (too strong a motor "
         "for its mass and time step: " +
         (model == RobotModel::kDiffDrive
              ? "lower robots.diff_drive.max_torque, raise "
                "robots.diff_drive.mass"
              : "lower physics.kp, raise physics.robot_mass") +
         " or lower physics.timestep)\n";
}

std::string NoArrivalWarning(const std::vector<long>& drives,
                             const std::vector<long>& timeouts,
                             const std::vector<long>& stalls, long moves,
                             const std::string& what) {
  const auto sum = [](const std::vector<long>& v) {
    return std::accumulate(v.begin(), v.end(), 0L);
  };
  const long asked = sum(drives), short_of = sum(timeouts) + sum(stalls);
  if (moves > 0 || asked == 0 || short_of < asked) return "";
  return "warning: " + what + ": no robot reached the lattice point it drove " +
         "to in " + std::to_string(asked) + " move" + (asked == 1 ? "" : "s") +
         " (" + std::to_string(sum(timeouts)) + " ended at " +
         "physics.step_timeout, " + std::to_string(sum(stalls)) +
         " stalled): the robots block each other or the walls, or cannot "
         "move with these settings (raise "
         "physics.step_timeout, or for wheeled robots "
         "robots.diff_drive.max_speed, max_turn_rate or the gains, or lower "
         "robots.diff_drive.mass)\n";
}

MjModelPtr CompileMjcf(const std::string& xml) {
  InstallMujocoHandlers();
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* name = "aia_model.xml";
  AIA_CHECK(
      mj_makeEmptyFileVFS(vfs.get(), name, static_cast<int>(xml.size())) == 0);
  const int idx = mj_findFileVFS(vfs.get(), name);
  std::memcpy(vfs->filedata[idx], xml.data(), xml.size());
  char error[1000] = "";
  mjModel* m = mj_loadXML(name, vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (m == nullptr)
    throw std::runtime_error(std::string("MuJoCo cannot compile the model: ") +
                             error);
  return MjModelPtr(m);
}

PhysicsModel::PhysicsModel(const World& world, const Scenario& scenario,
                           long contacts)
    : mjcf_(MakeMjcf(world, scenario, contacts)),
      physics_(scenario.physics),
      robot_model_(scenario.robots.model) {
  model_ = CompileMjcf(mjcf_);
  const MujocoModelSizes sizes = ModelSizesOf(world, scenario, contacts);
  hessians_ = sizes.solver.hessians;
  one_row_contacts_ = sizes.one_row_contacts;
  for (int i = 0; i < world.NumRobots(); ++i)
    starts_.push_back(world.map.lattice().Point(world.robot_starts[i]));
  driver_ = MakeRobotDriver(model_.get(), scenario, starts_);
  for (int k = 0; k < world.NumTargets(); ++k) {
    const int body = mj_name2id(model_.get(), mjOBJ_BODY,
                                ("target" + std::to_string(k)).c_str());
    AIA_CHECK(body >= 0 && model_->body_mocapid[body] >= 0);
    mocap_id_.push_back(model_->body_mocapid[body]);
  }
}

Simulation::Simulation(std::shared_ptr<const PhysicsModel> model)
    : model_(std::move(model)) {
  AIA_CHECK(model_ != nullptr);
  InstallMujocoHandlers();
  m_ = model_->model();
  data_ = MjDataPtr(mj_makeData(m_));
  if (data_ == nullptr)
    throw PhysicsError("MuJoCo cannot allocate the simulation's data");
  driver_ = model_->driver_.get();
  waypoints_ = model_->starts_;
  robot_stalls_.assign(waypoints_.size(), 0);
  robot_timeouts_.assign(waypoints_.size(), 0);
  retired_.assign(waypoints_.size(), 0);
  turning_.assign(waypoints_.size(), 0);
  state_.assign(waypoints_.size(), RobotState::kParked);
  since_.assign(waypoints_.size(), 0);
  progress_.assign(waypoints_.size(), 0.0);
  stuck_.assign(waypoints_.size(), 0);
  grace_.assign(waypoints_.size(), 0);
  mj_forward(m_, data_.get());
  IndexRayGeoms();
}

void Simulation::IndexRayGeoms() {
  // mj_ray's own rules (engine_ray.c, ray_eliminate) for which geoms a ray
  // with this group and flg_static = 1 tests: in the group, not invisible
  // by rgba or material. Any that is not a static primitive (mesh, height
  // field, plane, a moving body) sends every ray to mj_ray.
  std::vector<Box> bounds;
  ray_geoms_.clear();
  for (int i = 0; i < 4; ++i) {  // world/mjcf.cc's border walls
    const int body =
        mj_name2id(m_, mjOBJ_BODY, ("wall" + std::to_string(i)).c_str());
    border_geoms_[i] =
        body >= 0 && m_->body_geomnum[body] == 1 ? m_->body_geomadr[body] : -1;
  }
  const auto border = [&](int g) {
    return std::find(border_geoms_.begin(), border_geoms_.end(), g) !=
           border_geoms_.end();
  };  // g >= 0 below
  Vec2 lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  for (int g = 0; g < m_->ngeom; ++g) {
    const int group = std::clamp(m_->geom_group[g], 0, mjNGROUP - 1);
    if (group != kGroupObstacle || border(g)) continue;
    const int mat = m_->geom_matid[g];
    if (mat < 0 ? m_->geom_rgba[4 * g + 3] == 0
                : m_->mat_rgba[4 * mat + 3] == 0)
      continue;
    const int type = m_->geom_type[g];
    if (type == mjGEOM_MESH || type == mjGEOM_HFIELD || type == mjGEOM_PLANE ||
        m_->body_weldid[m_->geom_bodyid[g]] != 0) {
      ray_indexed_ = false;
      return;
    }
    const mjtNum* p = data_->geom_xpos + 3 * g;
    // The bounding sphere, a little larger: a hit on the segment lies in it.
    const double r = m_->geom_rbound[g] * (1.0 + 1e-9) + 1e-9;
    const Box b{Vec2(p[0] - r, p[1] - r), Vec2(p[0] + r, p[1] + r)};
    bounds.push_back(b);
    ray_geoms_.push_back(g);
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  if (ray_geoms_.empty()) lo = hi = Vec2(0.0, 0.0);
  ray_buckets_.Build(lo, hi, 1.0, bounds);
  ray_indexed_ = true;
}

void Simulation::StepPhysics() {
  driver_->Drive(waypoints_, data_.get(), &turning_);
  mjData* d = data_.get();
  const int nq = m_->nq, nv = m_->nv, na = m_->na;
  saved_.resize(1 + nq + 2 * nv + na);
  mjtNum* s = saved_.data();
  s[0] = d->time;
  CopyArray(d->qpos, nq, s + 1);
  CopyArray(d->qvel, nv, s + 1 + nq);
  CopyArray(d->qacc_warmstart, nv, s + 1 + nq + nv);
  CopyArray(d->act, na, s + 1 + nq + 2 * nv);
  while (true) {
    const auto t0 = std::chrono::steady_clock::now();
    mj_step(m_, d);
    physics_seconds_ += SecondsSince(t0);
    if (d->warning[mjWARN_CONTACTFULL].number == 0 &&
        d->warning[mjWARN_CNSTRFULL].number == 0)
      break;
    // Contacts were dropped: undo the step and take it again with room.
    d->time = s[0];
    CopyArray(s + 1, nq, d->qpos);
    CopyArray(s + 1 + nq, nv, d->qvel);
    CopyArray(s + 1 + nq + nv, nv, d->qacc_warmstart);
    CopyArray(s + 1 + nq + 2 * nv, na, d->act);
    Grow();
    d = data_.get();
  }
  ++mj_steps_;
  ++clock_;
  contacts_summed_ += d->ncon;
  max_contacts_ = std::max(max_contacts_, d->ncon);
  max_constraints_ = std::max(max_constraints_, d->nefc);
  max_stack_ = std::max<long>(max_stack_, d->maxuse_stack);
  for (int w = 0; w < mjNWARNING; ++w) {
    if (d->warning[w].number == 0) continue;
    warnings_[w] += d->warning[w].number;
    d->warning[w].number = 0;
  }
}

void Simulation::Grow() {
  const MujocoSizes sizes =
      MujocoSizesFor(m_->nbody, m_->nv, 2L * m_->nconmax, model_->hessians_,
                     model_->one_row_contacts_);
  const double bytes = MujocoDataBytes(sizes, m_->nv, m_->nu);
  if (bytes > kMaxPhysicsBytes) {
    char what[400];
    std::snprintf(
        what, sizeof(what),
        "the robots' contacts need more than %d in one physics "
        "step, and MuJoCo 2.2 would need %.1f GiB for them (its "
        "constraint arrays grow with the square of the contacts; "
        "the limit is %.1f GiB, what one mjData holds): fewer robots, or "
        "more room",
        m_->nconmax, bytes / (1L << 30), kMaxPhysicsBytes / (1L << 30));
    throw std::runtime_error(what);
  }
  MjModelPtr grown(mj_copyModel(nullptr, m_));
  grown->nconmax = sizes.nconmax;
  grown->njmax = sizes.njmax;
  grown->nstack = static_cast<int>(std::min<long>(sizes.nstack, INT_MAX));
  MjDataPtr data(mj_makeData(grown.get()));
  if (data == nullptr)
    throw PhysicsError("MuJoCo cannot allocate the simulation's data");
  const mjModel* m = grown.get();
  const mjData* from = data_.get();
  mjData* to = data.get();
  to->time = from->time;
  CopyArray(from->qpos, m->nq, to->qpos);
  CopyArray(from->qvel, m->nv, to->qvel);
  CopyArray(from->act, m->na, to->act);
  CopyArray(from->qacc_warmstart, m->nv, to->qacc_warmstart);
  CopyArray(from->ctrl, m->nu, to->ctrl);
  CopyArray(from->qfrc_applied, m->nv, to->qfrc_applied);
  CopyArray(from->xfrc_applied, 6 * m->nbody, to->xfrc_applied);
  CopyArray(from->mocap_pos, 3 * m->nmocap, to->mocap_pos);
  CopyArray(from->mocap_quat, 4 * m->nmocap, to->mocap_quat);
  max_stack_ = std::max<long>(max_stack_, from->maxuse_stack);
  data_ = std::move(data);
  own_model_ = std::move(grown);
  m_ = own_model_.get();
  ++grows_;
}

PhysicsMemoryStats Simulation::memory() const {
  PhysicsMemoryStats s;
  s.nconmax = m_->nconmax;
  s.njmax = m_->njmax;
  s.grows = grows_;
  s.max_contacts = max_contacts_;
  s.max_constraints = max_constraints_;
  s.max_stack = std::max<long>(max_stack_, data_->maxuse_stack);
  s.nstack = m_->nstack;
  s.data_bytes = static_cast<double>(data_->nbuffer);
  return s;
}

Simulation::Simulation(const World& world, const Scenario& scenario)
    : Simulation(std::make_shared<const PhysicsModel>(world, scenario)) {}

Vec2 Simulation::RobotPosition(int i) const {
  return driver_->Position(data_.get(), i);
}

Vec2 Simulation::RobotVelocity(int i) const {
  return driver_->Velocity(data_.get(), i);
}

double Simulation::RobotHeading(int i) const {
  return driver_->Heading(data_.get(), i);
}

double Simulation::ToGo(int i) const {
  return driver_->ToGo(data_.get(), i, waypoints_[i]);
}

bool Simulation::Slow(int i, double speed) const {
  return driver_->Slow(data_.get(), i, speed);
}

void Simulation::SetWaypoint(int i, const Vec2& p) { waypoints_[i] = p; }

Vec2 Simulation::TargetPosition(int k) const {
  const mjtNum* p = data_->mocap_pos + 3 * model_->mocap_id_[k];
  return {p[0], p[1]};
}

void Simulation::SetTargetPosition(int k, const Vec2& p) {
  mjtNum* q = data_->mocap_pos + 3 * model_->mocap_id_[k];
  q[0] = p.x();
  q[1] = p.y();
}

namespace {
// This slow and not there: blocked; never before kSettleTime into a move.
constexpr double kStallSpeed = PhysicsConfig::kStallSpeed;
constexpr double kSettleTime = PhysicsConfig::kSettleTime;

// Timesteps of dt in `seconds`, rounded up but not for a quotient's
// rounding (0.56 / 0.005 is 112.00000000000001); at least one.
long TimestepsFor(double seconds, double dt) {
  return std::max(1L, static_cast<long>(std::ceil(seconds / dt - 1e-9)));
}
}  // namespace

PhysicsStepStats Simulation::AdvanceToWaypoints(
    const std::function<void(double)>& on_substep) {
  PhysicsStepStats stats;
  const PhysicsConfig& physics = model_->physics();
  const double dt = m_->opt.timestep;
  const int max_steps =
      static_cast<int>(TimestepsFor(physics.StepTimeout(robot_model()), dt));
  const double tol = physics.tolerance;
  const double tol2 = tol * tol;
  // A robot in a sliding contact can creep on for seconds faster than
  // kStallSpeed: it is stuck too when what it has to go has not shrunk by
  // the driver's EnoughProgress over the last progress window.
  const double progress_window = driver_->progress_window();  // s
  const int check_every =
      std::max(1, static_cast<int>(std::lround(progress_window / dt)));
  const int n = num_robots();
  progress_.resize(n);
  stuck_.assign(n, 0);
  grace_.resize(n);
  for (int i = 0; i < n; ++i) {
    progress_[i] = ToGo(i);
    grace_[i] = GraceSteps(i, dt);
  }
  // A retired robot counts as arrived: nothing waits for it.
  auto arrived = [&](int i) {
    return retired_[i] ||
           (RobotPosition(i) - waypoints_[i]).squaredNorm() <= tol2;
  };
  auto settled = [&](int i, double elapsed) {
    return elapsed >= kSettleTime + grace_[i] * dt &&
           (stuck_[i] || Slow(i, kStallSpeed));
  };
  double elapsed = 0.0;
  bool all_settled = false;
  for (int s = 0; s < max_steps; ++s) {
    StepPhysics();
    ++stats.substeps;
    elapsed = (s + 1) * dt;
    if (on_substep) on_substep(elapsed);
    if ((s + 1) % check_every == 0) {
      for (int i = 0; i < n; ++i) {
        const double d = ToGo(i);
        const double enough = driver_->EnoughProgress(progress_[i], tol);
        // A window that began while the robot braked is not judged.
        stuck_[i] =
            s + 1 - check_every >= grace_[i] && progress_[i] - d < enough ? 1
                                                                          : 0;
        progress_[i] = d;
      }
    }
    bool all_arrived = true;
    all_settled = true;
    for (int i = 0; i < n; ++i) {
      if (arrived(i)) {
        time_use_.arrived += dt;
        continue;
      }
      all_arrived = false;
      if (settled(i, elapsed)) {
        time_use_.blocked += dt;
      } else {
        all_settled = false;
        (turning_[i] ? time_use_.turning : time_use_.driving) += dt;
      }
    }
    if (all_arrived) {
      stats.all_arrived = true;
      return stats;
    }
    if (all_settled) break;
  }
  stats.timed_out = !all_settled;
  // Who ended short: blocked, or (at the timeout) still on the way.
  for (int i = 0; i < n; ++i) {
    if (arrived(i)) continue;
    if (settled(i, elapsed)) {
      ++stats.stalled;
      ++robot_stalls_[i];
    } else {
      ++stats.late;
      ++robot_timeouts_[i];
    }
  }
  return stats;
}

void Simulation::StartMove(int i, const Vec2& p) {
  waypoints_[i] = p;
  state_[i] = RobotState::kMoving;
  since_[i] = clock_;
  progress_[i] = ToGo(i);
  stuck_[i] = 0;
  grace_[i] = GraceSteps(i, m_->opt.timestep);
}

long Simulation::GraceSteps(int i, double dt) const {
  const double seconds = driver_->BrakeSeconds(data_.get(), i);
  return seconds > 0.0 ? static_cast<long>(std::ceil(seconds / dt)) : 0;
}

void Simulation::Hold(int i, long until, bool yielding) {
  state_[i] = yielding ? RobotState::kYielding : RobotState::kHolding;
  since_[i] = until;
}

void Simulation::Park(int i) { state_[i] = RobotState::kParked; }

PhysicsStepStats Simulation::AdvanceMoves(
    long until, std::vector<int>* ended,
    const std::function<void(double)>& on_substep) {
  PhysicsStepStats stats;
  ended->clear();
  const PhysicsConfig& physics = model_->physics();
  const double dt = m_->opt.timestep;
  const long timeout = TimestepsFor(physics.StepTimeout(robot_model()), dt);
  const double tol2 = physics.tolerance * physics.tolerance;
  const long settle = TimestepsFor(kSettleTime, dt);
  const long check_every = std::max(
      1L, static_cast<long>(std::lround(driver_->progress_window() / dt)));
  const int n = num_robots();
  auto end = [&](int i) {
    ended->push_back(i);
    state_[i] = RobotState::kParked;
  };
  while (clock_ < until) {
    StepPhysics();
    ++stats.substeps;
    if (on_substep) on_substep(clock_seconds());
    for (int i = 0; i < n; ++i) {
      switch (state_[i]) {
        case RobotState::kParked:
          time_use_.arrived += dt;
          break;
        case RobotState::kHolding:
        case RobotState::kYielding:
          (state_[i] == RobotState::kHolding ? time_use_.staying
                                             : time_use_.yielding) += dt;
          if (clock_ >= since_[i]) end(i);
          break;
        case RobotState::kMoving: {
          const long elapsed = clock_ - since_[i];
          if (elapsed > 0 && elapsed % check_every == 0) {
            const double d = ToGo(i);
            // A window that began while the robot braked is not judged.
            stuck_[i] = elapsed - check_every >= grace_[i] &&
                        progress_[i] - d < driver_->EnoughProgress(
                                               progress_[i], physics.tolerance);
            progress_[i] = d;
          }
          if ((RobotPosition(i) - waypoints_[i]).squaredNorm() <= tol2) {
            // The substep it arrived in was spent on the way.
            (turning_[i] ? time_use_.turning : time_use_.driving) += dt;
            end(i);
          } else if (elapsed >= settle + grace_[i] &&
                     (stuck_[i] || Slow(i, kStallSpeed))) {
            time_use_.blocked += dt;
            ++stats.stalled;
            ++robot_stalls_[i];
            end(i);
          } else if (elapsed >= timeout) {
            (turning_[i] ? time_use_.turning : time_use_.driving) += dt;
            ++stats.late;
            ++robot_timeouts_[i];
            end(i);
          } else {
            (turning_[i] ? time_use_.turning : time_use_.driving) += dt;
          }
          break;
        }
      }
    }
    if (!ended->empty()) break;
  }
  stats.timed_out = stats.late > 0;
  stats.all_arrived = false;
  return stats;
}

bool Simulation::RayClear(const Vec2& from, const Vec2& to) const {
  const mjtNum pnt[3] = {from.x(), from.y(), kSensorHeight};
  const mjtNum vec[3] = {to.x() - from.x(), to.y() - from.y(), 0.0};
  mjtByte groups[mjNGROUP] = {0};
  groups[kGroupObstacle] = 1;
  // Nothing lies between a point and itself: a target exactly at the robot
  // (a listed target on its start, a moving target onto a resting robot)
  // is in sight. mj_ray refuses so short a ray with an error.
  if (mju_norm3(vec) < mjMINVAL) return true;
  // The ray length is |vec|, so a hit before 1 lies between the two points.
  if (ray_indexed_) {
    return !ray_buckets_.Any(from.cwiseMin(to), from.cwiseMax(to), [&](int i) {
      const int g = ray_geoms_[i];
      const mjtNum x =
          mju_rayGeom(data_->geom_xpos + 3 * g, data_->geom_xmat + 9 * g,
                      m_->geom_size + 3 * g, pnt, vec, m_->geom_type[g]);
      return x >= 0.0 && x < 1.0;
    });
  }
  int geom = -1;
  // Static geoms included (obstacles are static bodies). The nearest hit
  // being a border wall's means nothing lies before the wall, which the
  // segment can only touch at its end.
  const mjtNum x = mj_ray(m_, data_.get(), pnt, vec, groups, 1, -1, &geom);
  if (geom >= 0 && std::find(border_geoms_.begin(), border_geoms_.end(),
                             geom) != border_geoms_.end())
    return true;
  return x < 0.0 || x >= 1.0;
}

void Sense(const Simulation& sim, const SensorModel& sensor,
           const std::vector<Vec2>& robots, const std::vector<Vec2>& targets,
           const std::vector<std::uint8_t>& active, std::vector<Rng>* rngs,
           std::vector<std::vector<Measurement>>* out) {
  SensingScratch scratch;
  Sense(sim, sensor, robots, targets, active, rngs, out, &scratch);
}

void Sense(const Simulation& sim, const SensorModel& sensor,
           const std::vector<Vec2>& robots, const std::vector<Vec2>& targets,
           const std::vector<std::uint8_t>& active, std::vector<Rng>* rngs,
           std::vector<std::vector<Measurement>>* out,
           SensingScratch* scratch) {
  const int n = static_cast<int>(robots.size());
  out->resize(n);
  // The targets in range of each robot through a grid of the targets, in
  // ascending order as a loop over all of them would find them.
  scratch->targets.Build(targets, sensor.range);
  for (int i = 0; i < n; ++i) {
    auto& z = (*out)[i];
    z.clear();
    if (!active[i]) continue;
    std::vector<int>& near = scratch->near;
    near.clear();
    scratch->targets.Near(targets, robots[i], sensor.range, &near);
    for (const int k : near) {
      const Vec2 rel = targets[k] - robots[i];
      const double d2 = rel.squaredNorm();
      if (sensor.line_of_sight && !sim.RayClear(robots[i], targets[k]))
        continue;
      Rng& rng = (*rngs)[i];
      const double sd = sensor.Std(std::sqrt(d2));
      Measurement m;
      m.target = k;
      m.y = rel + sd * Vec2(rng.Normal(), rng.Normal());
      m.precision = sensor.Precision(m.y.norm());
      z.push_back(m);
    }
  }
}

}  // namespace aia
