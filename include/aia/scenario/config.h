// Typed configuration of one mission, filled from a scenario YAML file
// (SPEC section 10). Every default lives here, as a default member value, and
// nowhere else. docs/scenarios.md documents each key.
#ifndef AIA_SCENARIO_CONFIG_H_
#define AIA_SCENARIO_CONFIG_H_

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "aia/core/types.h"

namespace aia {

struct RandomObstaclesConfig {
  int count = 30;
  Vec2 min_size{0.4, 0.4};
  Vec2 max_size{2.0, 2.0};
};

struct BoxConfig {
  Vec2 center{0.0, 0.0};
  Vec2 size{1.0, 1.0};
};

struct WorkspaceConfig {
  Vec2 size{20.0, 20.0};  // metres
  double cell = 0.1;      // occupancy grid cell, metres
  // Obstacles: any combination of the three sources.
  std::optional<RandomObstaclesConfig> random;
  std::vector<BoxConfig> boxes;
  std::string
      map;  // absolute path of a PGM/PNG image (dark = occupied), or empty
  double map_threshold =
      0.5;  // pixels darker than this fraction of white are occupied
};

struct RobotsConfig {
  int count = 0;  // required
  double radius = 0.15;
  double step = 0.5;        // lattice spacing and move length, metres
  std::vector<Vec2> start;  // empty: random free lattice points
};

struct SensorConfig {
  double range = 2.0;
  double eta = 0.05;     // noise std grows by eta per metre of distance
  double sigma0 = 0.01;  // noise std at zero distance
  bool line_of_sight = true;
};

// x(t+1) = A x(t) + b + w, w ~ N(0, q I). The state is the target's position
// (dimension 2) or position and velocity [px, py, vx, vy] (dimension 4).
struct DynamicsConfig {
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(2, 2);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(2);
  double q = 0.0;

  int dim() const { return static_cast<int>(A.rows()); }
  bool IsStatic() const;
};

struct TargetConfig {
  Vec2 position{0.0, 0.0};
  Vec2 velocity{0.0,
                0.0};  // initial velocity; used when the state has dimension 4
  std::optional<Vec2> prior_mean;  // default: truth plus a draw from the prior
  std::optional<double> prior_sigma;  // default: TargetsConfig::prior_sigma
  DynamicsConfig dynamics;
};

struct TargetsConfig {
  int count = 0;  // random static targets (when `list` is empty)
  std::vector<TargetConfig> list;  // explicit targets
  double prior_sigma = 1.0;        // prior std per coordinate
  // Std (metres) of a default prior mean's offset from the truth: targets
  // without `prior_mean` get truth + N(0, prior_offset^2 I).
  double prior_offset = 0.5;
};

struct MissionConfig {
  double eps = 0.1;  // success: for every target, min_i det Sigma_i^k <= eps
  int max_steps = 400;
  bool stop_at_success = true;
};

struct FailureConfig {
  int robot = -1;  // -1: a robot drawn at random (from the scenario seed)
  int step = 0;
};

enum class CommMode { kFull, kRange };

struct CommunicationConfig {
  CommMode mode = CommMode::kFull;
  double range = 4.0;  // r_com for kRange
  double kappa_self = 0.75;
  double packet_loss_lambda =
      0.0;  // Poisson mean of directed edges lost per step
  std::vector<FailureConfig> failures;
};

struct PolicyConfig {
  std::string name = "greedy";
  std::string model;  // absolute path, for learned policies
  // Expert (C-SB) settings; used by later issues.
  std::map<std::string, double> params;
};

struct PhysicsConfig {
  double timestep = 0.005;    // seconds
  double kp = 200.0;          // waypoint actuator stiffness, N/m
  double robot_mass = 0.25;   // kg; with kp gives the tracking bandwidth
  double tolerance = 0.01;    // metres: a robot has arrived within this
  double step_timeout = 1.0;  // seconds of simulated time per decision step
};

struct RenderConfig {
  int width = 640;
  int height = 480;
  int fps = 30;
  int follow_robot = -1;  // robot whose uncertainty heatmap is drawn; -1: none
};

// One mission. `file` and `lines` let later stages (world validation, policy
// lookup) report errors at the line of the offending key.
struct Scenario {
  std::string name = "scenario";
  std::uint64_t seed = 0;
  WorkspaceConfig workspace;
  RobotsConfig robots;
  SensorConfig sensor;
  TargetsConfig targets;
  MissionConfig mission;
  CommunicationConfig communication;
  PolicyConfig policy;
  PhysicsConfig physics;
  RenderConfig render;

  std::string file;  // the YAML file it came from ("" if built in code)
  std::map<std::string, int>
      lines;  // dotted key -> 1-based line, e.g. "robots.start[2]"

  int NumTargets() const {
    return targets.list.empty() ? targets.count
                                : static_cast<int>(targets.list.size());
  }
  // Line of a key, or of its nearest recorded parent, or 0.
  int LineOf(const std::string& key) const;
};

}  // namespace aia

#endif  // AIA_SCENARIO_CONFIG_H_
