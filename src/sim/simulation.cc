#include "aia/sim/simulation.h"

#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "aia/core/check.h"
#include "aia/world/mjcf.h"

namespace aia {

MjModelPtr CompileMjcf(const std::string& xml) {
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

PhysicsModel::PhysicsModel(const World& world, const Scenario& scenario)
    : mjcf_(MakeMjcf(world, scenario)), physics_(scenario.physics) {
  model_ = CompileMjcf(mjcf_);
  const int n = world.NumRobots();
  for (int i = 0; i < n; ++i) {
    const std::string robot = "robot" + std::to_string(i);
    const int jx =
        mj_name2id(model_.get(), mjOBJ_JOINT, (robot + "_x").c_str());
    const int ax =
        mj_name2id(model_.get(), mjOBJ_ACTUATOR, (robot + "_x").c_str());
    AIA_CHECK(jx >= 0 && ax >= 0);
    starts_.push_back(world.map.lattice().Point(world.robot_starts[i]));
    qpos_adr_.push_back(model_->jnt_qposadr[jx]);
    qvel_adr_.push_back(model_->jnt_dofadr[jx]);
    ctrl_adr_.push_back(ax);
  }
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
  data_ = MjDataPtr(mj_makeData(model_->model()));
  waypoints_ = model_->starts_;
  mj_forward(model_->model(), data_.get());
}

Simulation::Simulation(const World& world, const Scenario& scenario)
    : Simulation(std::make_shared<const PhysicsModel>(world, scenario)) {}

Vec2 Simulation::RobotPosition(int i) const {
  const mjtNum* q = data_->qpos + model_->qpos_adr_[i];
  return model_->starts_[i] + Vec2(q[0], q[1]);
}

Vec2 Simulation::RobotVelocity(int i) const {
  const mjtNum* v = data_->qvel + model_->qvel_adr_[i];
  return {v[0], v[1]};
}

void Simulation::SetWaypoint(int i, const Vec2& p) {
  waypoints_[i] = p;
  const Vec2& start = model_->starts_[i];
  data_->ctrl[model_->ctrl_adr_[i]] = p.x() - start.x();
  data_->ctrl[model_->ctrl_adr_[i] + 1] = p.y() - start.y();
}

Vec2 Simulation::TargetPosition(int k) const {
  const mjtNum* p = data_->mocap_pos + 3 * model_->mocap_id_[k];
  return {p[0], p[1]};
}

void Simulation::SetTargetPosition(int k, const Vec2& p) {
  mjtNum* q = data_->mocap_pos + 3 * model_->mocap_id_[k];
  q[0] = p.x();
  q[1] = p.y();
}

PhysicsStepStats Simulation::AdvanceToWaypoints(
    const std::function<void(double)>& on_substep) {
  PhysicsStepStats stats;
  const mjModel* m = model_->model();
  const PhysicsConfig& physics = model_->physics();
  const double dt = m->opt.timestep;
  const int max_steps =
      std::max(1, static_cast<int>(std::ceil(physics.step_timeout / dt)));
  const double tol2 = physics.tolerance * physics.tolerance;
  const double stall_speed =
      0.01;  // m/s: a robot this slow and not there is blocked
  const double settle_time =
      0.05;  // s: a robot is never called stalled before this
  const int n = num_robots();
  for (int s = 0; s < max_steps; ++s) {
    const auto t0 = std::chrono::steady_clock::now();
    mj_step(m, data_.get());
    physics_seconds_ +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
            .count();
    ++mj_steps_;
    ++stats.substeps;
    const double elapsed = (s + 1) * dt;
    if (on_substep) on_substep(elapsed);
    bool all_arrived = true, all_settled = true;
    for (int i = 0; i < n; ++i) {
      if ((RobotPosition(i) - waypoints_[i]).squaredNorm() <= tol2) continue;
      all_arrived = false;
      if (elapsed < settle_time ||
          RobotVelocity(i).squaredNorm() > stall_speed * stall_speed) {
        all_settled = false;
        break;
      }
    }
    if (all_arrived) {
      stats.all_arrived = true;
      return stats;
    }
    if (all_settled) return stats;
  }
  stats.timed_out = true;
  return stats;
}

bool Simulation::RayClear(const Vec2& from, const Vec2& to) const {
  const mjtNum pnt[3] = {from.x(), from.y(), kSensorHeight};
  const mjtNum vec[3] = {to.x() - from.x(), to.y() - from.y(), 0.0};
  mjtByte groups[mjNGROUP] = {0};
  groups[kGroupObstacle] = 1;
  int geom = -1;
  // Static geoms included (obstacles are static bodies); the ray length is
  // |vec|, so a hit before 1 lies between the two points.
  const mjtNum x =
      mj_ray(model_->model(), data_.get(), pnt, vec, groups, 1, -1, &geom);
  return x < 0.0 || x >= 1.0;
}

void Sense(const Simulation& sim, const SensorModel& sensor,
           const std::vector<Vec2>& robots, const std::vector<Vec2>& targets,
           const std::vector<std::uint8_t>& active, std::vector<Rng>* rngs,
           std::vector<std::vector<Measurement>>* out) {
  const int n = static_cast<int>(robots.size());
  out->resize(n);
  const double range2 = sensor.range * sensor.range;
  for (int i = 0; i < n; ++i) {
    auto& z = (*out)[i];
    z.clear();
    if (!active[i]) continue;
    for (int k = 0; k < static_cast<int>(targets.size()); ++k) {
      const Vec2 rel = targets[k] - robots[i];
      const double d2 = rel.squaredNorm();
      if (d2 > range2) continue;
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
